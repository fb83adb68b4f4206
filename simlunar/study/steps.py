"""Checkpoints inside a study: finished sub-steps kept, so an interrupted study resumes.

A long study is a sequence of sub-steps whose results do not depend on each other's order
except through a shared random stream (the structured-light capture draws every frame's
noise from one generator): the sampling study's strategies, the scanner study's coded scans
and its (scan mode, planner) rescans, the LIDAR study's planners. Each is run through
:func:`resumable` with a :class:`Steps` store: a finished step is saved with the state of the
shared generators after it, and on a rerun it is loaded instead of computed and the
generators are set to that state, so the steps after it draw exactly what an uninterrupted
study draws. Results are therefore bit-identical to an uninterrupted run.

The store decides where the steps live and for which inputs they hold: the pipeline keeps
them in the unit's working folder under the unit's cache key (a changed configuration or
input file is another key, never these steps); :class:`MemorySteps` keeps them in a dict.
The study only names its steps. Arrays only: no files here.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from typing import Any, Protocol

import numpy as np

__all__ = ["MemorySteps", "Steps", "resumable"]


class Steps(Protocol):
    """Where a study's finished sub-steps are kept."""

    def load(self, name: str) -> Any | None:
        """The value saved under ``name``, or None (never saved, or unreadable)."""

    def save(self, name: str, value: Any) -> None:
        """Keep ``value`` under ``name`` (atomically: a Ctrl-C never leaves half a step)."""


class MemorySteps:
    """Steps kept in a dict (deep copies: a loaded value shares nothing with the saved one).

    Attributes
    ----------
    saved : dict name -> value
    loads : list of str
        The names loaded, in order (what a resumed study did not compute).
    """

    def __init__(self):
        self.saved: dict[str, Any] = {}
        self.loads: list[str] = []

    def load(self, name: str) -> Any | None:
        if name not in self.saved:
            return None
        self.loads.append(name)
        return copy.deepcopy(self.saved[name])

    def save(self, name: str, value: Any) -> None:
        self.saved[name] = copy.deepcopy(value)


def resumable(
    steps: Steps | None,
    name: str,
    compute: Callable[[], Any],
    *,
    streams: Sequence[np.random.Generator] = (),
) -> tuple[Any, bool]:
    """The value of step ``name``: loaded from ``steps`` or computed (then saved).

    Parameters
    ----------
    steps : Steps or None
        None: always computed, nothing saved.
    name : str
        The step's name, unique within the study.
    compute : callable () -> value
        The step (its value must be picklable for a store that writes files).
    streams : sequence of numpy Generators
        Shared random streams the step draws from: their states after the step are saved
        with it and restored when it is loaded.

    Returns
    -------
    (value, loaded) : the step's value and whether it came from ``steps``.
    """
    if steps is not None:
        kept = steps.load(name)
        if (
            isinstance(kept, dict)
            and set(kept) == {"value", "streams"}
            and len(kept["streams"]) == len(streams)
        ):
            for g, state in zip(streams, kept["streams"]):
                g.bit_generator.state = state
            return kept["value"], True
    value = compute()
    if steps is not None:
        states = [g.bit_generator.state for g in streams]
        steps.save(name, {"value": value, "streams": states})
    return value, False
