"""The study kinds a work unit runs: ``study.kind`` -> the unit's study (its sensor, records).

One entry per kind of :data:`STUDY_UNITS` (a :class:`simlunar.registry.Registry`): ``kind ->
Entry(unit function, library options class, meta)``. The unit function is
``unit(cfg, scene, seeds, timings, steps, **kw) -> UnitRecord`` (:mod:`simlunar.pipeline.unit`:
``scene`` the unit's :class:`~simlunar.pipeline.figure_inputs.RenderScene`, ``seeds`` its stage
seeds, ``timings`` the dict it adds its stage seconds to, ``steps`` where its study keeps
finished sub-steps); the options class is the study's own (what ``config.translate`` builds
from the YAML section). Meta: ``parallel=True`` for a kind whose study spreads its tasks over
forked workers (it is given ``workers=``), ``renders=True`` for a kind whose study renders
throughout (it runs under the render lock), ``config`` the schema model of its section.

:func:`study_unit` is the decorator that registers a unit function; :func:`run_study_unit` is
the dispatch of :func:`simlunar.pipeline.unit.compute_unit`.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable

from simlunar.pipeline.figure_inputs import RENDER_LOCK
from simlunar.registry import Registry

__all__ = ["STUDY_UNITS", "run_study_unit", "study_unit"]

#: study kind -> its unit function and the study's options class
STUDY_UNITS = Registry("study kind")


def study_unit(kind: str, options: type, **meta) -> Callable:
    """Register the decorated unit function as the unit of study ``kind`` (see the module)."""

    def register(fn: Callable) -> Callable:
        STUDY_UNITS.register(kind, fn, options, summary=(fn.__doc__ or "").strip(), **meta)
        return fn

    return register


def run_study_unit(cfg, scene, seeds, timings, steps, *, workers: int = 1):
    """The unit record of ``cfg.study``'s kind: its registered unit function run on the
    rendered ``scene`` (with ``workers`` for a parallel kind, under the render lock for one
    that renders throughout)."""
    entry = STUDY_UNITS[cfg.study.kind]
    kw = {"workers": workers} if entry.meta.get("parallel") else {}
    lock = RENDER_LOCK if entry.meta.get("renders") else contextlib.nullcontext()
    with lock:
        return entry.target(cfg, scene, seeds, timings, steps, **kw)
