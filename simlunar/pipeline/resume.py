"""Computing a run's missing units, and keeping the finished sub-steps of a unit cut short.

Finished units are cached whole (:class:`~simlunar.results.store.UnitCache`). Inside a long
unit, the study keeps its finished sub-steps (:mod:`simlunar.study.steps`: the sampling
study's strategies, the scanner study's coded scans and (scan mode, planner) rescans, the
LIDAR study's planners) in the unit's working folder ``<out>/units/<key>.steps/``, one file per
step, written atomically. The folder is named by the unit's cache key, which covers the
resolved configuration, the hashes of the files it reads and the simlunar version, so a
changed configuration or input never reads these steps; each file also repeats the key and
its step name, and is read only if both match. A Ctrl-C keeps them; the rerun of the same
command loads them, computes only the remaining steps and gives results bit-identical to an
uninterrupted run. The folder is removed once its unit is cached, and with the units a run
no longer produces.

Steps are pickles (they hold scans, not only numbers): they are scratch files of an
interrupted run of this folder, read back only by a rerun into the same folder; a rerun that
cannot read one (another library version, a damaged file) simply computes that step again.

Progress: the units' bar or lines of :mod:`simlunar.pipeline.progress`, and inside a unit the
events of :mod:`simlunar.progress` when the unit runs in this process.
"""

from __future__ import annotations

import json
import pickle
import re
import shutil
from pathlib import Path
from typing import Any

from simlunar.atomic import atomic_write_bytes
from simlunar.errors import InfrastructureError, InputChangedError, RunInterrupted
from simlunar.interrupts import interrupted
from simlunar.pipeline.executors import LocalPoolExecutor, SerialExecutor, accepts_keyword
from simlunar.pipeline.progress import _progress
from simlunar.progress import Event
from simlunar.results.array_exports import write_array_export
from simlunar.results.exports import write_scan_export
from simlunar.results.store import UNITS_DIR, UnitCache

__all__ = ["STEPS_SUFFIX", "UnitSteps", "compute_missing", "kept_message", "prune_steps"]

#: a unit's working folder is ``units/<key><STEPS_SUFFIX>``
STEPS_SUFFIX = ".steps"
_FORMAT = 1


class UnitSteps:
    """The finished sub-steps of one unit, one file each in its working folder.

    Parameters
    ----------
    folder : path
        ``<out>/units/<key>.steps`` (created on the first save).
    key : str
        The unit's cache key: written into every step and checked when it is read.

    Attributes
    ----------
    loaded, saved : list of str
        Step names read back and written by this object, in order.
    """

    def __init__(self, folder: str | Path, key: str):
        self.folder = Path(folder)
        self.key = str(key)
        self.loaded: list[str] = []
        self.saved: list[str] = []

    def _path(self, name: str) -> Path:
        # a readable, collision-free file name: the name's safe characters and its index
        # in a hash would do, but the name itself is checked inside the file anyway
        safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "step"
        return self.folder / f"{safe}.pkl"

    def load(self, name: str) -> Any | None:
        """The step ``name`` of this unit, or None (absent, unreadable, or another's)."""
        path = self._path(name)
        try:
            with open(path, "rb") as f:
                kept = pickle.load(f)
        except FileNotFoundError:
            return None
        except Exception:  # a damaged or foreign step is computed again
            return None
        if not isinstance(kept, dict) or (
            kept.get("format"),
            kept.get("key"),
            kept.get("name"),
        ) != (_FORMAT, self.key, name):
            return None
        self.loaded.append(name)
        return kept["value"]

    def save(self, name: str, value: Any) -> None:
        """Keep step ``name`` (atomically: a Ctrl-C leaves the old file or the new one)."""
        blob = pickle.dumps(
            {"format": _FORMAT, "key": self.key, "name": name, "value": value},
            protocol=pickle.HIGHEST_PROTOCOL,
        )
        atomic_write_bytes(self._path(name), blob, make_parents=True)
        self.saved.append(name)

    def clear(self) -> None:
        """Remove the folder (its unit is cached)."""
        shutil.rmtree(self.folder, ignore_errors=True)


def steps_folder(out: str | Path, key: str) -> Path:
    """The working folder of unit ``key`` in result folder ``out``."""
    return Path(out) / UNITS_DIR / f"{key}{STEPS_SUFFIX}"


def prune_steps(out: str | Path, keep: set[str]) -> list[Path]:
    """Remove the working folders of units not in ``keep`` (keys); the removed folders."""
    units = Path(out) / UNITS_DIR
    if not units.is_dir():
        return []
    gone = []
    for p in sorted(units.glob(f"*{STEPS_SUFFIX}")):
        if p.is_dir() and p.name[: -len(STEPS_SUFFIX)] not in keep:
            shutil.rmtree(p, ignore_errors=True)
            gone.append(p)
    return gone


def _payload(run, u) -> dict:
    """What a unit's compute gets: its config, the hashes of its inputs and, where it runs
    in this process (it can write into the folder), its working folder for steps."""
    payload = {"config": u.config, "inputs": u.inputs}
    if isinstance(run.executor, (SerialExecutor, LocalPoolExecutor)):
        payload["steps"] = {"folder": str(steps_folder(run.out, u.key)), "key": u.key}
    return payload


def _hook(bar):
    """The within-unit listener: events of :mod:`simlunar.progress`, or the older
    ``(stage, done, total)`` calls of a compute function written before them."""

    def hook(*args):
        if len(args) == 1 and isinstance(args[0], Event):
            bar.event(args[0])
        else:
            name, done, total = args
            bar.event(Event((str(name),), int(done), total, "steps"))

    return hook


def compute_missing(run, cache: UnitCache, todo, records: dict, n_cached: int) -> None:
    """Compute the ``todo`` units of ``run`` (:class:`simlunar.pipeline.runner._Run`) on its
    executor, caching each (and its scan export) as it comes, then removing its steps; its
    record is added to ``records``. A Ctrl-C or a cluster failure says what is kept."""
    out, total = run.out, len(run.units)
    bar = _progress(run.progress, total, n_cached, run.cfg.name)
    n_new = 0
    try:
        # with the input hashes of each unit's key: the unit checks the files it reads
        payloads = [_payload(run, u) for u in todo]
        hook = _hook(bar) if bar is not None and accepts_keyword(run.compute, "progress") else None
        # executors written against the older two-argument run() still work without a hook
        kw = {"progress": hook} if hook is not None else {}
        for i, result in run.executor.run(run.compute, payloads, **kw):
            u = todo[i]
            arrays = result.pop("arrays", {}) or {}
            scans = result.pop("scans", None)
            if scans is not None:  # before the cache entry: a cached unit has its scans
                write_scan_export(out / "scans" / f"unit{u.index}", scans, unit_key=u.key)
            exports = result.pop("exports", None)
            if exports is not None:  # the reconstructions of --save-arrays, before caching too
                write_array_export(out / "arrays" / f"unit{u.index}", exports, unit_key=u.key)
            record = {**result, "index": u.index, "sweep": u.sweep, "config": u.config}
            cache.save(u.key, record, arrays)
            records[u.key] = json.loads(json.dumps(record, default=float))
            UnitSteps(steps_folder(out, u.key), u.key).clear()  # the unit stands whole now
            n_new += 1
            if bar is not None:
                bar.advance()
    except BaseException as exc:
        done = n_cached + n_new
        if isinstance(exc, KeyboardInterrupt) or interrupted():
            # a Ctrl-C, whatever the interrupted code made of it (the renderer's start-up
            # turns it into other errors)
            raise RunInterrupted(kept_message(out, done, total, "interrupted")) from None
        if isinstance(exc, InfrastructureError):
            raise InfrastructureError(f"{exc}; {kept_message(out, done, total)}") from None
        if isinstance(exc, InputChangedError):
            raise InputChangedError(f"{exc}; {kept_message(out, done, total)}") from None
        raise
    finally:
        if bar is not None:
            bar.stop()
    if interrupted():  # a Ctrl-C swallowed by the code it interrupted
        raise RunInterrupted(kept_message(out, n_cached + n_new, total, "interrupted"))


def kept_message(out: Path, done: int, total: int, what: str = "") -> str:
    """What a stopped run kept: its finished units and the steps of unfinished ones."""
    head = f"{what}: " if what else ""
    units = Path(out) / UNITS_DIR
    steps = sum(1 for p in units.glob(f"*{STEPS_SUFFIX}/*.pkl")) if units.is_dir() else 0
    within = f" (and {steps} finished steps of unfinished units)" if steps else ""
    return (
        f"{head}{done} of {total} units finished and kept in {out / 'units'}{within}; "
        "rerun the same command to resume"
    )
