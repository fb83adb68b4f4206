"""The one study protocol: guide image -> planner -> sensor -> reconstruction -> metrics.

For every planner label, trial and sample budget: the planner chooses guide pixels (from the
guide image, or nothing for a sensor that needs no plan), the sensor measures range there and
says what it cost (:class:`~simlunar.sensors.base.Acquisition`), the measured cells are
reconstructed to the full grid by Delaunay-linear interpolation and scored against the truth.
The sampling study (ideal sensor, paper section 4) and the scanner study (structured light,
section 5) are this loop with their own planners, seeds and scores; so is any new sensor.

Arrays only: no files, no configuration objects.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import signal
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass

import numpy as np

from simlunar.errors import InfrastructureError
from simlunar.reconstruction import OUTSIDE_POLICIES, reconstruct
from simlunar.sensors.base import Acquisition, Sensor

__all__ = ["Outcome", "Planner", "Trials", "run_protocol"]

#: a planner of the protocol: ``planner(k, rng) -> (k, 2) int64 (row, col)`` guide pixels.
#: A planner that measures while it plans (multi-round: it asks the sensor back) has
#: ``measures = True`` and ``planner.acquire(k, sensor, plan_rng, sensor_rng) -> (Acquisition,
#: rounds)`` instead; it reads the scene through ``sensor.acquire`` only.
Planner = Callable[[int, object], np.ndarray]
#: scores of one reconstruction: ``evaluate(recon (rows, cols), acquisition) -> {metric: value}``
Evaluate = Callable[[np.ndarray, Acquisition], dict]
#: seeds of one (label, trial, budget index): ``(planner rng, sensor rng)``
Seeds = Callable[[str, int, int], tuple]


@dataclass(frozen=True)
class Trials:
    """What the protocol repeats: planner labels x trials x sample budgets.

    Attributes
    ----------
    planners : mapping label -> Planner or None
        None for a sensor that needs no plan (then ``ks`` is ``[0]``-like and ignored).
    ks : sequence of int
        Sample counts (one per budget / density).
    trials : int >= 1
    seeds : Seeds
        Independent randomness per (label, trial, budget index).
    """

    planners: Mapping[str, Planner | None]
    ks: Sequence[int]
    trials: int
    seeds: Seeds

    def __post_init__(self):
        if isinstance(self.trials, bool) or int(self.trials) < 1:
            raise ValueError(f"trials must be an integer >= 1, got {self.trials!r}")
        if not self.planners:
            raise ValueError("the protocol needs at least one planner label")


@dataclass(frozen=True, eq=False)
class Outcome:
    """One (label, trial, budget) of the protocol: what was measured and its scores."""

    label: str
    trial: int
    budget_index: int
    k: int
    acquisition: Acquisition
    scores: dict
    rounds: int = 1


def run_protocol(
    sensor: Sensor,
    trials: Trials,
    evaluate: Evaluate,
    *,
    outside: str = "nearest",
    workers: int = 1,
) -> Iterator[list[Outcome]]:
    """Run the protocol; yields, per (label, trial) task in order, its outcomes per budget.

    Parameters
    ----------
    sensor : Sensor
        Bound to the scene (its truth or its capture).
    trials : Trials
    evaluate : Evaluate
        Scores of a reconstruction (and of its acquisition: valid fraction, bit errors).
    outside : {"nearest", "nan"}
        Reconstruction policy outside the measured cells' convex hull.
    workers : int
        Forked processes running (label, trial) tasks in parallel (a sensor that renders
        keeps 1); results do not depend on it, every task having its own seeds.
    """
    if outside not in OUTSIDE_POLICIES:
        raise ValueError(
            f"unknown outside policy {outside!r}; valid: {', '.join(OUTSIDE_POLICIES)}"
        )
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    state = {"sensor": sensor, "trials": trials, "evaluate": evaluate, "outside": outside}
    tasks = [(label, t) for label in trials.planners for t in range(int(trials.trials))]
    return _map_tasks(state, tasks, workers)


def _task_outcomes(state, label: str, trial: int) -> list[Outcome]:
    """Every budget of one (label, trial): plan, acquire, reconstruct, score."""
    sensor, tr = state["sensor"], state["trials"]
    planner = tr.planners[label]
    out = []
    for bi, k in enumerate(tr.ks):
        plan_rng, sensor_rng = tr.seeds(label, trial, bi)
        rounds = 1
        if getattr(planner, "measures", False):
            acq, rounds = planner.acquire(k, sensor, plan_rng, sensor_rng)
        else:
            rc = None if planner is None else planner(k, plan_rng)
            acq = sensor.acquire(rc, rng=sensor_rng)
        recon = reconstruct(acq.rc, acq.values, acq.shape, outside=state["outside"])
        out.append(Outcome(label, trial, bi, k, acq, state["evaluate"](recon, acq), rounds))
    return out


_STATE: dict = {}


def _init_worker(state):
    # Ctrl-C reaches the whole process group: the parent stops the pool, so a worker must not
    # print its own KeyboardInterrupt traceback
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _STATE.clear()
    _STATE.update(state)


def _worker_task(task):
    # in a worker, only the scores travel back (the acquisition's arrays stay)
    return [
        Outcome(o.label, o.trial, o.budget_index, o.k, _light(o.acquisition), o.scores, o.rounds)
        for o in _task_outcomes(_STATE, *task)
    ]


def _light(acq: Acquisition) -> Acquisition:
    return Acquisition(np.empty((0, 2)), np.empty(0), acq.shape, acq.frames, acq.seconds)


def _map_tasks(state, tasks, workers):
    """Per (label, trial) outcomes, in task order; a fork pool when workers > 1."""
    if workers == 1 or len(tasks) == 1:
        return (_task_outcomes(state, *t) for t in tasks)
    methods = multiprocessing.get_all_start_methods()
    # fork shares the arrays with the workers without pickling them
    ctx = multiprocessing.get_context("fork" if "fork" in methods else None)
    _warm_kernels(state["outside"])
    # concurrent.futures notices a dead worker (multiprocessing.Pool waits for it forever)
    pool = cf.ProcessPoolExecutor(
        min(workers, len(tasks)), mp_context=ctx, initializer=_init_worker, initargs=(state,)
    )
    try:
        out = list(pool.map(_worker_task, tasks))
    except BrokenProcessPool:
        _stop(pool)
        raise InfrastructureError(
            "a study worker process died (killed by the system, e.g. out of memory, "
            "or by an operator)"
        ) from None
    except BaseException:
        _stop(pool)  # Ctrl-C: the workers ignore SIGINT, so end them instead of waiting
        raise
    pool.shutdown(wait=True)
    return iter(out)


def _stop(pool: cf.ProcessPoolExecutor) -> None:
    """End a pool's workers now (their tasks are abandoned) and release it."""
    # the executor has no public way to end running workers; _processes is {pid: Process}
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        try:
            proc.terminate()
        except (OSError, ValueError):
            pass  # already gone
    pool.shutdown(wait=False, cancel_futures=True)


def _warm_kernels(outside: str) -> None:
    """Call the compiled reconstruction once before forking: the children then never enter
    Numba's dispatcher lock, which another thread of this process (a concurrent unit of
    LocalPoolExecutor) may hold at the moment of the fork."""
    pts = np.array([[0, 0], [0, 2], [2, 0], [2, 2]])
    reconstruct(pts, np.arange(4.0), (3, 3), outside=outside)
