"""The one study protocol: guide image -> planner -> sensor -> reconstructions -> metrics.

For every planner label, trial and sample budget: the planner chooses guide pixels (from the
guide image, or nothing for a sensor that needs no plan), the sensor measures range there and
says what it cost (:class:`~simlunar.sensors.base.Acquisition`), and EVERY configured
reconstruction (:data:`simlunar.reconstruction.RECONSTRUCTIONS`; by default the
Delaunay-linear interpolation of the paper alone) fills the full grid from the same measured
cells, with the guide (:class:`~simlunar.reconstruction.Guide`: what the camera saw) for the
reconstructions that read it; each is scored against the truth. Every reconstruction of one
acquisition sees the same samples, so their scores are paired.
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
from simlunar.reconstruction import (
    OUTSIDE_POLICIES,
    RECONSTRUCTIONS,
    Guide,
    reconstruct,
    run_reconstruction,
)
from simlunar.sensors.base import Acquisition, Sensor
from simlunar.study.reconstruction_spec import ReconstructionSpec

__all__ = [
    "DEFAULT_RECONSTRUCTION",
    "Outcome",
    "Planner",
    "Trials",
    "exposure_count",
    "guide_cost",
    "light_outcome",
    "outcome_rows",
    "reconstruction_of",
    "reconstruction_options",
    "run_protocol",
]

#: the reconstruction every study ran before reconstructions were configurable (paper 4.1)
DEFAULT_RECONSTRUCTION = "linear"

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
    """One (label, trial, budget) of the protocol: what was measured and its scores.

    Attributes
    ----------
    scores : dict metric -> float
        Scores of the FIRST configured reconstruction (``linear`` by default): what a caller
        that runs one reconstruction reads.
    recon_scores : dict reconstruction -> dict metric -> float
        Scores of every configured reconstruction, in the configured order.
    recon_info : dict reconstruction -> dict
        What each reconstruction reported about itself (:attr:`Reconstructed.info`, e.g.
        ``shading_share``), plus ``guide_frames`` (the guide frames it read, a tuple of names;
        empty for an image-free reconstruction) and ``exposures`` (their count: each frame is
        one camera exposure).
    grids : dict reconstruction -> ndarray float32 (rows, cols), or None
        The reconstructed grids themselves, only for the trial ``run_protocol(keep_trial=)``
        names (exports); None otherwise.
    """

    label: str
    trial: int
    budget_index: int
    k: int
    acquisition: Acquisition
    scores: dict
    rounds: int = 1
    recon_scores: dict | None = None
    recon_info: dict | None = None
    grids: dict | None = None

    def __post_init__(self):
        if self.recon_scores is None:
            object.__setattr__(self, "recon_scores", {DEFAULT_RECONSTRUCTION: self.scores})
        if self.recon_info is None:
            info = {n: {"guide_frames": (), "exposures": 0} for n in self.recon_scores}
            object.__setattr__(self, "recon_info", info)


def reconstruction_options(
    reconstructions: Mapping | Sequence | None = None, *, outside: str = "nearest"
) -> dict:
    """``name -> options object`` of the reconstructions to run, in order.

    Parameters
    ----------
    reconstructions : mapping label -> (options object, mapping of its fields, or None), or a
        sequence of ``study.reconstructions`` items (names, ``{label: options}`` mappings or
        :class:`~simlunar.study.reconstruction_spec.ReconstructionSpec`); None: ``{"linear":
        None}`` (the paper's). A mapping of fields may name its registered reconstruction
        (``reconstruction``: a label of its own).
    outside : {"nearest", "nan"}
        The ``outside`` policy of ``linear`` when its options do not name one (the studies'
        own ``outside`` option, kept for the callers that set it).

    Raises
    ------
    ValueError
        An unknown name (listing the valid ones), a stray option key or a bound broken.
    """
    if reconstructions is None:
        reconstructions = {DEFAULT_RECONSTRUCTION: None}
    if isinstance(reconstructions, str):
        raise ValueError(
            f"reconstructions must be a list or mapping of names, got the string "
            f"{reconstructions!r}"
        )
    if not isinstance(reconstructions, Mapping):
        specs = [s if isinstance(s, ReconstructionSpec) else ReconstructionSpec.parse(s)
                 for s in reconstructions]  # fmt: skip
        names = [s.label for s in specs]
        if len(set(names)) != len(names):
            raise ValueError(f"reconstructions must be distinct names, got {names}")
        reconstructions = {s.label: s.values() or None for s in specs}
    if not reconstructions:
        raise ValueError("the protocol needs at least one reconstruction")
    out = {}
    for name, opts in reconstructions.items():
        if opts is not None and not isinstance(opts, Mapping):
            base = reconstruction_of(opts)  # an options object names its reconstruction
        else:
            # a label of its own: {label: {reconstruction: <registered name>, options...}}
            spec = ReconstructionSpec.parse({name: opts})
            base, opts = spec.name, dict(spec.options)
            if spec.labelled and name in RECONSTRUCTIONS:
                raise ValueError(
                    f"label {name!r} is the name of another reconstruction; choose another"
                )
        entry = RECONSTRUCTIONS[base]  # unknown: a ValueError listing the valid names
        if opts is None or isinstance(opts, Mapping):
            values = dict(opts or {})
            if base == DEFAULT_RECONSTRUCTION:
                values.setdefault("outside", outside)
            opts = entry.make_options(values)
        elif not isinstance(opts, entry.options):
            raise TypeError(
                f"reconstruction {name!r} takes {entry.options.__name__}, got {type(opts).__name__}"
            )
        out[str(name)] = opts
    return out


def reconstruction_of(options) -> str:
    """The registered reconstruction an options object belongs to (each entry has its own
    options class, so a labelled reconstruction is run by its options' entry)."""
    for name, entry in RECONSTRUCTIONS.items():
        if type(options) is entry.options:
            return name
    raise TypeError(f"{type(options).__name__} is the options class of no reconstruction")


def guide_cost(name: str, guide: Guide | None, info: Mapping | None = None) -> tuple:
    """``(frames, exposures)`` a reconstruction read: the frames its info names (``frames``)
    or, for a guided reconstruction that names none, every frame of the guide; an image-free
    one reads none. One frame is one camera exposure."""
    if guide is None or not RECONSTRUCTIONS[name].meta.get("guided"):
        return (), 0
    frames = (info or {}).get("frames")
    if frames is None:
        frames = guide.frames
    elif isinstance(frames, str):
        frames = tuple(f for f in frames.split("+") if f)
    frames = tuple(str(f) for f in frames)
    return frames, exposure_count(frames)


def exposure_count(frames) -> int:
    """Camera exposures behind the frames a reconstruction read: the distinct frames named,
    a derived frame (the ratio ``sun/sun2``) naming the frames it is made of, so it costs no
    exposure of its own (``sun``, ``sun2`` and ``sun/sun2`` are 2 exposures, not 3).

    ``frames``: names, or one ``+``-joined string (a results row's ``guide_frames``)."""
    if isinstance(frames, str):
        frames = frames.split("+")
    return len({part for f in frames for part in str(f).split("/") if part})


def outcome_rows(
    oc: Outcome,
    head: Mapping,
    middle: Mapping,
    tail: Mapping | None = None,
    *,
    metrics: Sequence[str] | None = None,
    value: Callable | None = None,
) -> list[dict]:
    """The tidy rows of one outcome, every study kind's: one per (reconstruction, metric).

    A row is ``head`` (the kind's label columns), ``reconstruction``, the guide frames it read
    (``guide_frames``, ``+``-joined names, and ``exposures``; only for a reconstruction that
    read any), ``middle`` (the budget columns), ``trial``, ``metric``, ``value`` and ``tail``
    (the acquisition's cost columns).

    Parameters
    ----------
    metrics : sequence of str, optional
        The metrics in row order (default: each reconstruction's scores in their order).
    value : callable, optional
        Applied to each score (e.g. ``float``); default the score as it is.
    """
    rows = []
    for r, scores in oc.recon_scores.items():
        cost = _cost_columns(oc.recon_info[r])
        for m in scores if metrics is None else metrics:
            v = scores[m] if value is None else value(scores[m])
            rows.append({**head, "reconstruction": r, **cost, **middle, "trial": oc.trial,
                         "metric": m, "value": v, **(tail or {})})  # fmt: skip
    return rows


def _cost_columns(info: Mapping) -> dict:
    """The guide-frame columns of a row: none for a reconstruction that read no frame."""
    if not info.get("guide_frames"):
        return {}
    return {"guide_frames": "+".join(info["guide_frames"]), "exposures": int(info["exposures"])}


def run_protocol(
    sensor: Sensor,
    trials: Trials,
    evaluate: Evaluate,
    *,
    outside: str = "nearest",
    workers: int = 1,
    reconstructions: Mapping | Sequence | None = None,
    guide: Guide | None = None,
    keep_trial: int | None = None,
) -> Iterator[list[Outcome]]:
    """Run the protocol; yields, per (label, trial) task in order, its outcomes per budget.

    Parameters
    ----------
    sensor : Sensor
        Bound to the scene (its truth or its capture).
    trials : Trials
    evaluate : Evaluate
        Scores of a reconstruction (and of its acquisition: valid fraction, bit errors); called
        once per reconstruction with its grid. An evaluator with compiled kernels may have a
        ``warm()`` method: called before workers are forked.
    outside : {"nearest", "nan"}
        Policy of ``linear`` outside the measured cells' convex hull (unless its options in
        ``reconstructions`` name one).
    workers : int
        Forked processes running (label, trial) tasks in parallel (a sensor that renders
        keeps 1); results do not depend on it, every task having its own seeds.
    reconstructions : mapping name -> options (object, mapping or None), or names, optional
        The reconstructions run on every acquisition, in order (:func:`reconstruction_options`);
        default ``linear`` alone.
    guide : Guide, optional
        What the camera saw, on the acquisitions' grid; required by a guided reconstruction.
        The sample values reach the reconstruction as the sensor measured them (a camera
        distance -- depth -- falls where height rises: a reconstruction that relates the
        samples to the image must fit a signed gain, as the shading calibration does).
    keep_trial : int, optional
        The outcomes of this trial carry their reconstructed grids (:attr:`Outcome.grids`,
        float32) for an export; None (default): no grid is kept. Changes no score.
    """
    if outside not in OUTSIDE_POLICIES:
        raise ValueError(
            f"unknown outside policy {outside!r}; valid: {', '.join(OUTSIDE_POLICIES)}"
        )
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    recons = reconstruction_options(reconstructions, outside=outside)
    for name, opts in recons.items():
        if RECONSTRUCTIONS[reconstruction_of(opts)].meta.get("guided") and guide is None:
            raise ValueError(f"reconstruction {name!r} needs the guide image (guide=Guide(...))")
    state = {
        "sensor": sensor,
        "trials": trials,
        "evaluate": evaluate,
        "outside": outside,
        "reconstructions": recons,
        "guide": guide,
        "keep_trial": keep_trial,
    }
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
        keep = state.get("keep_trial") == trial
        scores, info, grids = _reconstruct_all(state, acq, keep=keep)
        first = next(iter(scores.values()))
        out.append(Outcome(label, trial, bi, k, acq, first, rounds, scores, info, grids))
    return out


def _reconstruct_all(state, acq: Acquisition, *, keep: bool = False):
    """Every configured reconstruction of one acquisition, scored; what each reported; and,
    with ``keep``, the reconstructed grids (float32; else None)."""
    guide = state["guide"]
    scores, infos = {}, {}
    grids = {} if keep else None
    for name, opts in state["reconstructions"].items():
        base = reconstruction_of(opts)
        rec = run_reconstruction(base, acq.rc, acq.values, acq.shape, guide=guide, options=opts)
        scores[name] = state["evaluate"](rec.heights, acq)
        info = dict(rec.info)
        frames, exposures = guide_cost(base, guide, info)
        info.pop("frames", None)
        infos[name] = {**info, "guide_frames": frames, "exposures": exposures}
        if grids is not None:
            grids[name] = np.asarray(rec.heights, np.float32)
    return scores, infos, grids


_STATE: dict = {}


def _init_worker(state):
    # Ctrl-C reaches the whole process group: the parent stops the pool, so a worker must not
    # print its own KeyboardInterrupt traceback
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _STATE.clear()
    _STATE.update(state)


def _worker_task(task):
    # in a worker, only the scores (and kept grids) travel back (the acquisition's arrays stay)
    return [light_outcome(o) for o in _task_outcomes(_STATE, *task)]


def light_outcome(o: Outcome) -> Outcome:
    """``o`` without its acquisition's samples (its cost and any kept grids kept): what
    crosses a process boundary or goes into a checkpoint when only the scores are needed."""
    return Outcome(o.label, o.trial, o.budget_index, o.k, _light(o.acquisition), o.scores,
                   o.rounds, o.recon_scores, o.recon_info, o.grids)  # fmt: skip


def _light(acq: Acquisition) -> Acquisition:
    return Acquisition(np.empty((0, 2)), np.empty(0), acq.shape, acq.frames, acq.seconds,
                       energy_j=acq.energy_j)  # fmt: skip


def _map_tasks(state, tasks, workers):
    """Per (label, trial) outcomes, in task order; a fork pool when workers > 1."""
    if workers == 1 or len(tasks) == 1:
        return (_task_outcomes(state, *t) for t in tasks)
    methods = multiprocessing.get_all_start_methods()
    # fork shares the arrays with the workers without pickling them
    ctx = multiprocessing.get_context("fork" if "fork" in methods else None)
    _warm_kernels(state["outside"], state["reconstructions"], state["guide"])
    warm = getattr(state["evaluate"], "warm", None)
    if warm is not None:  # an evaluator's own compiled kernels
        warm()
    # concurrent.futures notices a dead worker (multiprocessing.Pool waits for it forever)
    pool = cf.ProcessPoolExecutor(
        min(workers, len(tasks)), mp_context=ctx, initializer=_init_worker, initargs=(state,)
    )
    return _pool_results(pool, _submit_all(pool, tasks))


def _worker_died(pool: cf.ProcessPoolExecutor) -> InfrastructureError:
    _stop(pool)
    return InfrastructureError(
        "a study worker process died (killed by the system, e.g. out of memory, or by an operator)"
    )


def _submit_all(pool: cf.ProcessPoolExecutor, tasks) -> list:
    """Every task's future; a worker that dies while tasks are still being handed out (the pool
    refuses the rest) is the same one-line error as one that dies later."""
    try:
        return [pool.submit(_worker_task, t) for t in tasks]
    except BrokenProcessPool:
        raise _worker_died(pool) from None


def _pool_results(pool: cf.ProcessPoolExecutor, futures: list) -> Iterator[list[Outcome]]:
    """The pool's outcomes in task order, each as soon as it and those before it are done
    (a caller keeps finished tasks before the last one ends)."""
    try:
        for future in futures:
            yield future.result()
    except BrokenProcessPool:
        raise _worker_died(pool) from None
    except BaseException:
        _stop(pool)  # Ctrl-C: the workers ignore SIGINT, so end them instead of waiting
        raise
    pool.shutdown(wait=True)


def _stop(pool: cf.ProcessPoolExecutor) -> None:
    """End a pool's workers now (their tasks are abandoned) and release it."""
    # The executor has no public way to end running workers (_processes is {pid: Process}).
    # Ending them makes its manager thread mark every pending future failed, which raises
    # InvalidStateError in that thread for a future already cancelled (CPython 3.11
    # terminate_broken): so nothing here cancels a future (no Executor.map, whose iterator
    # cancels on close, and no cancel_futures).
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        try:
            proc.terminate()
        except (OSError, ValueError):
            pass  # already gone
    pool.shutdown(wait=False)


def _warm_kernels(outside: str, reconstructions: Mapping | None = None, guide=None) -> None:
    """Call the compiled reconstructions once before forking: the children then never enter
    Numba's dispatcher lock, which another thread of this process (a concurrent unit of
    LocalPoolExecutor) may hold at the moment of the fork. Each configured reconstruction runs
    once on a small corner of the guide (best effort: one that refuses so small a grid is
    compiled in the children instead)."""
    pts = np.array([[0, 0], [0, 2], [2, 0], [2, 2]])
    reconstruct(pts, np.arange(4.0), (3, 3), outside=outside)
    for name, opts in (reconstructions or {}).items():
        if name == DEFAULT_RECONSTRUCTION:
            continue
        small = None
        if guide is not None and min(guide.shape) >= 8:
            small = Guide(guide.image[:8, :8], light=guide.light, spacing=guide.spacing,
                          frames=guide.frames)  # fmt: skip
        r, c = np.mgrid[0:8:3, 0:8:3]
        rc = np.stack([r.ravel(), c.ravel()], axis=-1)
        try:
            run_reconstruction(name, rc, np.zeros(len(rc)), (8, 8), guide=small, options=opts)
        except ValueError:
            pass
