"""Checkpoints inside a study: finished sub-steps kept, so an interrupted study resumes.

A long study is a sequence of sub-steps whose results do not depend on each other's order
except through a shared random stream (the structured-light capture draws every frame's
noise from one generator): the sampling study's strategies, the scanner study's coded scans
and its (scan mode, planner) rescans, the LIDAR study's planners. Each is kept in a
:class:`Steps` store (:func:`resumable` for one sub-step): a finished step is saved with the
state of the shared generators after it, and on a rerun it is loaded instead of computed and
the generators are set to that state, so the steps after it draw exactly what an
uninterrupted study draws. Results are therefore bit-identical to an uninterrupted run.

Every study kind runs its protocol labels (the sampling study's strategies, a scan mode's
planners, the LIDAR study's planners) through the one wrapper :class:`ProtocolSteps`: one
step per label, holding the label's tidy rows (made by the kind's row function, see
:func:`simlunar.study.protocol.outcome_rows`) and what the kind keeps of each outcome; a
label kept by an earlier run is loaded, the others are run together (a forked pool may run
them in parallel) and each is kept as soon as its last trial is back. A step an older run
kept in another form is run again, never misread.

The store decides where the steps live and for which inputs they hold: the pipeline keeps
them in the unit's working folder under the unit's cache key (a changed configuration or
input file is another key, never these steps); :class:`MemorySteps` keeps them in a dict.
The study only names its steps. Arrays only: no files here.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from simlunar.study.protocol import Outcome, Trials, light_outcome

__all__ = ["LabelStep", "MemorySteps", "ProtocolSteps", "Steps", "resumable"]


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
    kept = _load(steps, name, streams)
    if kept is not None:
        return _restore(kept, streams), True
    value = compute()
    _save(steps, name, value, streams)
    return value, False


def _load(steps: Steps | None, name: str, streams: Sequence, kind: type | None = None):
    """The kept ``{"value", "streams"}`` of step ``name`` when it has this study's shape (as
    many stream states; a value of ``kind``), else None (then the step is computed again)."""
    if steps is None:
        return None
    kept = steps.load(name)
    if (
        isinstance(kept, dict)
        and set(kept) == {"value", "streams"}
        and len(kept["streams"]) == len(streams)
        and (kind is None or isinstance(kept["value"], kind))
    ):
        return kept
    return None


def _restore(kept: dict, streams: Sequence[np.random.Generator]):
    """Set the shared streams to their states after the kept step; its value."""
    for g, state in zip(streams, kept["streams"]):
        g.bit_generator.state = state
    return kept["value"]


def _save(steps: Steps | None, name: str, value, streams: Sequence[np.random.Generator]) -> None:
    if steps is not None:
        steps.save(name, {"value": value, "streams": [g.bit_generator.state for g in streams]})


@dataclass(frozen=True, eq=False)
class LabelStep:
    """One protocol label of a study, run or loaded: the step :class:`ProtocolSteps` keeps.

    Attributes
    ----------
    label : str
    rows : list of dict
        Its tidy rows (the kind's row function over its outcomes, in task order).
    outcomes : list
        What the kind keeps of each outcome (default :func:`~simlunar.study.protocol.
        light_outcome`: scores, costs and kept grids, no samples), trial by trial, budget by
        budget.
    loaded : bool
        Whether it came from the store (an earlier run of this study) instead of being run.
    """

    label: str
    rows: list
    outcomes: list
    loaded: bool = False


class ProtocolSteps:
    """The one wrapper of a study's protocol: checkpoints, resume and rows of its labels.

    Parameters
    ----------
    steps : Steps or None
        Where the labels' steps are kept (None: nothing kept).
    names : mapping label -> step name
        The step of each label, unique within the study; the labels a previous run kept are
        loaded now (:attr:`kept`).
    streams : sequence of numpy Generators
        Shared random streams the labels draw from (the structured-light capture's noise):
        saved with each step and restored when it is loaded, so the labels run after it draw
        what an uninterrupted study draws.
    """

    def __init__(self, steps: Steps | None, names: Mapping[str, str], *, streams=()):
        self.steps = steps
        self.names = dict(names)
        self.streams = tuple(streams)
        self.kept = {}
        for label, name in self.names.items():
            kept = _load(steps, name, self.streams, LabelStep)
            if kept is not None:
                self.kept[label] = kept

    def run(
        self,
        trials: Trials,
        run: Callable[[Trials], Iterator[list[Outcome]]],
        *,
        rows: Callable[[Outcome], list[dict]],
        keep: Callable[[Outcome], Any] = light_outcome,
        advance: Callable[[int], None] | None = None,
    ) -> Iterator[LabelStep]:
        """Every label of ``trials`` in order: loaded, or run and then kept.

        Parameters
        ----------
        trials : Trials
            Its labels are those of ``names``.
        run : callable Trials -> iterator of outcome lists
            The protocol (:func:`~simlunar.study.protocol.run_protocol`) over the labels not
            kept: one list of outcomes (one per budget) per (label, trial) task, label by
            label; asked for each task only when it is needed.
        rows : callable Outcome -> list of dict
            The kind's tidy rows of one outcome.
        keep : callable Outcome -> object
            What a step keeps of each outcome (it must pickle).
        advance : callable (n), optional
            Told the acquisitions of every task run (its outcomes), for a progress bar.
        """
        todo = {lb: p for lb, p in trials.planners.items() if lb not in self.kept}
        tasks = iter(run(dataclasses.replace(trials, planners=todo))) if todo else iter(())
        for label in trials.planners:
            if label in self.kept:
                yield dataclasses.replace(_restore(self.kept[label], self.streams), loaded=True)
                continue
            got, kept = [], []
            for _ in range(int(trials.trials)):
                outcomes = next(tasks)
                for oc in outcomes:
                    got += rows(oc)
                    kept.append(keep(oc))
                if advance is not None:
                    advance(len(outcomes))
            step = LabelStep(label, got, kept)
            # every trial of this label done: kept, so a rerun starts after it
            _save(self.steps, self.names[label], step, self.streams)
            yield step
