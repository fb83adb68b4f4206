"""The study-kind registry: every kind of the schema has a unit, the dispatch hands a parallel
kind its workers and runs a rendering kind under the render lock, an unknown kind is refused
with the valid ones."""

from __future__ import annotations

import threading
import typing

import pytest

from simlunar.config.schema import ExperimentCfg
from simlunar.pipeline import study_kinds, unit
from simlunar.pipeline.figure_inputs import RENDER_LOCK
from simlunar.registry import Registry
from simlunar.study.lidar import LidarStudyOptions
from simlunar.study.sampling import SamplingStudyOptions
from simlunar.study.scanner import ScannerStudyOptions


def _schema_kinds() -> set[str]:
    """The ``kind`` literals of the models in the schema's ``study`` union."""
    kinds, todo = set(), [ExperimentCfg.model_fields["study"].annotation]
    while todo:
        t = todo.pop()
        fields = getattr(t, "model_fields", None)
        if fields is not None:
            kinds.update(typing.get_args(fields["kind"].annotation))
        else:
            todo.extend(typing.get_args(t))
    return kinds


def test_every_study_kind_of_the_schema_has_its_unit():
    assert _schema_kinds() == {"sampling", "scanner", "lidar"}
    assert set(study_kinds.STUDY_UNITS) == _schema_kinds()
    units = study_kinds.STUDY_UNITS
    assert units["sampling"].target is unit._sampling_unit
    assert units["scanner"].target is unit._scanner_unit
    assert units["lidar"].target is unit._lidar_unit
    assert units["sampling"].options is SamplingStudyOptions
    assert units["scanner"].options is ScannerStudyOptions
    assert units["lidar"].options is LidarStudyOptions
    # each entry names the schema model of its section, whose kind is the entry's name
    for kind, entry in units.items():
        assert typing.get_args(entry.meta["config"].model_fields["kind"].annotation) == (kind,)
    # only the sampling study forks workers; only the scanner renders throughout its study
    assert [k for k, e in units.items() if e.meta.get("parallel")] == ["sampling"]
    assert [k for k, e in units.items() if e.meta.get("renders")] == ["scanner"]


def _lock_held() -> bool:
    """Whether the render lock is held (by this thread: a reentrant lock; tried from another)."""
    got = []

    def attempt():
        got.append(RENDER_LOCK.acquire(blocking=False))
        if got[0]:
            RENDER_LOCK.release()

    t = threading.Thread(target=attempt)
    t.start()
    t.join()
    return not got[0]


class _Cfg:
    def __init__(self, kind):
        self.study = type("Study", (), {"kind": kind})()


def test_the_dispatch_follows_the_entry(monkeypatch):
    units = Registry("study kind")
    monkeypatch.setattr(study_kinds, "STUDY_UNITS", units)
    calls = []

    @study_kinds.study_unit("forks", SamplingStudyOptions, parallel=True)
    def forks(cfg, scene, seeds, timings, steps, *, workers):
        calls.append(("forks", workers, _lock_held()))
        return "a"

    @study_kinds.study_unit("renders", ScannerStudyOptions, renders=True)
    def renders(cfg, scene, seeds, timings, steps):
        calls.append(("renders", None, _lock_held()))
        return "b"

    assert study_kinds.run_study_unit(_Cfg("forks"), 0, {}, {}, None, workers=3) == "a"
    assert study_kinds.run_study_unit(_Cfg("renders"), 0, {}, {}, None, workers=3) == "b"
    assert calls == [("forks", 3, False), ("renders", None, True)]
    assert not _lock_held()
    with pytest.raises(ValueError, match=r"unknown study kind 'render'.*renders"):
        study_kinds.run_study_unit(_Cfg("render"), 0, {}, {}, None)
    with pytest.raises(ValueError, match="registered twice"):
        study_kinds.study_unit("forks", SamplingStudyOptions)(forks)
