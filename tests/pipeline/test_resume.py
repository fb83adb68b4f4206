"""Resuming inside a unit: a run cut short by Ctrl-C at a unit's second sub-step keeps the
first in the unit's working folder; the rerun computes only the missing sub-steps and writes a
``results.csv`` byte-identical to an uninterrupted run's; the folder goes once the unit is
cached, and a changed configuration never reads it. Also the step files themselves."""

from __future__ import annotations

import pickle

import pytest

import simlunar
from simlunar.config.schema import ExperimentCfg
from simlunar.errors import RunInterrupted
from simlunar.pipeline.resume import UnitSteps, kept_message, prune_steps, steps_folder
from simlunar.pipeline.runner import expand, run_experiment
from simlunar.study import protocol


def test_a_step_round_trips_and_a_foreign_or_damaged_one_reads_as_missing(tmp_path):
    steps = UnitSteps(tmp_path / "units" / "abc.steps", "abc")
    assert steps.load("scan mode gray_code planner ") is None
    value = {"rows": [{"value": 0.1 + 0.2}], "state": [1, 2]}
    steps.save("scan mode gray_code planner ", value)
    assert steps.load("scan mode gray_code planner ") == value
    assert steps.saved == steps.loaded == ["scan mode gray_code planner "]
    # another unit's key in the same file name: not this unit's step
    other = UnitSteps(tmp_path / "units" / "abc.steps", "abd")
    assert other.load("scan mode gray_code planner ") is None
    # two names that sanitise to one file: the name inside the file tells them apart
    steps.save("a/b", 1)
    assert steps.load("a b") is None and steps.load("a/b") == 1
    # a damaged file is computed again, not an error
    (tmp_path / "units" / "abc.steps" / "a_b.pkl").write_bytes(b"\x80\x05garbage")
    assert steps.load("a/b") is None
    # no temporary file is left beside the steps (atomic writes)
    assert sorted(p.name for p in steps.folder.iterdir()) == [
        "a_b.pkl",
        "scan_mode_gray_code_planner.pkl",
    ]
    steps.clear()
    assert not steps.folder.exists()


def test_prune_keeps_only_the_steps_of_units_still_to_compute(tmp_path):
    for key in ("k1", "k2"):
        UnitSteps(steps_folder(tmp_path, key), key).save("s", 1)
    (tmp_path / "units" / "k3.json").write_text("{}")  # a cached unit's file: not a step
    gone = prune_steps(tmp_path, {"k2"})
    assert [p.name for p in gone] == ["k1.steps"]
    assert sorted(p.name for p in (tmp_path / "units").iterdir()) == ["k2.steps", "k3.json"]
    assert prune_steps(tmp_path / "nothing", set()) == []
    assert "(and 1 finished steps of unfinished units)" in kept_message(tmp_path, 0, 1, "x")


def _cfg(**study):
    return ExperimentCfg.model_validate(
        {
            "name": "resume",
            "seed": 5,
            "terrain": {"preset": "aerial_1", "scale": 0.0625},
            "render": {"spp": 4},
            "study": {
                "strategies": ["random", "grid", "wavelet"],
                "densities": ["1/4", "1/16"],
                "trials": 2,
                "metrics": ["mse", "grad"],
                **study,
            },
            "figures": {"enabled": False},
        }
    )


@pytest.mark.render
def test_ctrl_c_at_the_second_strategy_then_rerun_is_byte_identical(tmp_path, monkeypatch):
    cfg = _cfg()
    (unit,) = expand(cfg)
    clean = tmp_path / "clean"
    run_experiment(cfg, clean, progress=False, figures=False)

    real = protocol._task_outcomes
    calls: list[str] = []
    stop = {"at": "grid"}

    def counted(state, label, trial):
        if label == stop["at"]:
            raise KeyboardInterrupt  # as a Ctrl-C while the second strategy computes
        calls.append(label)
        return real(state, label, trial)

    monkeypatch.setattr(protocol, "_task_outcomes", counted)
    out = tmp_path / "resumed"
    with pytest.raises(RunInterrupted, match="1 finished steps of unfinished units"):
        run_experiment(cfg, out, progress=False, figures=False)
    folder = steps_folder(out, unit.key)
    assert [p.name for p in folder.iterdir()] == ["sampling_strategy_random.pkl"]
    assert calls == ["random", "random"]

    stop["at"], calls[:] = None, []
    loaded: list[str] = []
    real_load = UnitSteps.load

    def load(self, name):
        value = real_load(self, name)
        if value is not None:
            loaded.append(name)
        return value

    monkeypatch.setattr(UnitSteps, "load", load)
    summary = run_experiment(cfg, out, progress=False, figures=False)
    assert summary.units_computed == 1
    # the kept strategy was loaded, only the others computed (each trial once)
    assert loaded == ["sampling strategy random"]
    assert sorted(calls) == ["grid", "grid", "wavelet", "wavelet"]
    assert (out / "results.csv").read_bytes() == (clean / "results.csv").read_bytes()
    assert not folder.exists()  # the unit is cached: its steps are gone


@pytest.mark.render
def test_steps_of_another_cache_key_are_never_read(tmp_path, monkeypatch):
    """Another key (here another library version; equally a changed input file or a
    configuration that changes a number) is another unit: its steps are pruned, not read."""
    cfg = _cfg()
    out = tmp_path / "r"
    real = protocol._task_outcomes

    def stop_at_grid(state, label, trial):
        if label == "grid":
            raise KeyboardInterrupt
        return real(state, label, trial)

    monkeypatch.setattr(protocol, "_task_outcomes", stop_at_grid)
    with pytest.raises(RunInterrupted):
        run_experiment(cfg, out, progress=False, figures=False)
    (unit,) = expand(cfg)
    assert steps_folder(out, unit.key).is_dir()
    monkeypatch.setattr(protocol, "_task_outcomes", real)
    monkeypatch.setattr(simlunar, "__version__", simlunar.__version__ + "+other")
    (other,) = expand(cfg)
    assert other.key != unit.key
    loaded: list[str] = []
    real_load = UnitSteps.load

    def load(self, name):
        value = real_load(self, name)
        if value is not None:
            loaded.append(name)
        return value

    monkeypatch.setattr(UnitSteps, "load", load)
    run_experiment(cfg, out, progress=False, figures=False)
    assert loaded == []  # nothing of the other key's steps
    assert not (out / "units" / f"{unit.key}.steps").exists()
    assert not (out / "units" / f"{other.key}.steps").exists()


def test_step_files_are_plain_pickles_of_key_name_and_value(tmp_path):
    steps = UnitSteps(tmp_path / "k.steps", "k")
    steps.save("x", [1.5])
    with open(tmp_path / "k.steps" / "x.pkl", "rb") as f:
        assert pickle.load(f) == {"format": 1, "key": "k", "name": "x", "value": [1.5]}
