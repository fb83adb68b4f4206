"""The LIDAR study's planners: every planner of the sampling study, fitted to a LIDAR.

A label of a LIDAR study plans, from the guide image, the guide pixels the sensor measures:

- an image strategy of :func:`simlunar.planner.plan` (its importance map per density: the
  learned map is predicted per density, :func:`~simlunar.study.sampling_planners.importance_maps`);
- an oracle (:data:`simlunar.planner.ORACLES`): it reads the guide view's true depth in the
  planner step only and is a bound, not a planner (its label starts ``oracle``, as in the
  sampling study); the real sensor then measures its beams as any planner's;
- ``sequential`` (:data:`simlunar.planner.MEASURING`, :class:`LidarRounds`): the LIDAR itself
  measures each round; the next round is planned from the measured ranges, and the rounds'
  scan times add up with the re-pointing between them (:func:`merge_rounds`); on a moving
  platform a steered beam's rounds continue its trajectory
  (:class:`~simlunar.sensors.rounds.PlatformRounds`);
- any of those fitted to the sensor (:class:`SensorFit`).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from simlunar.lidar.join import join_scans
from simlunar.lidar.planning import (
    fit_to_budget,
    fit_to_time,
    receiver_capped_layout,
    receiver_capped_plan,
)
from simlunar.planner import MEASURING, ORACLES, PLANNERS, map_of, plan
from simlunar.planner.strategies import MIN_K
from simlunar.registry import Options, option
from simlunar.sensors.base import Acquisition
from simlunar.study.protocol import reconstruction_options
from simlunar.study.sampling_planners import (
    MeasuringPlanner,
    importance_maps,
    measuring_planner,
    oracle_reconstruction,
)

__all__ = [
    "FITS",
    "LidarRounds",
    "SensorFit",
    "budget_cost",
    "lidar_planners",
    "merge_rounds",
    "planned_values",
]

#: the sensor-aware planning rules of :class:`SensorFit`
FITS = ("scan_time", "budget", "receiver")


@dataclass(frozen=True)
class SensorFit(Options):
    """A planner label fitted to its sensor (:mod:`simlunar.lidar.planning`).

    ``scan_time`` (tour-aware, any plan-directed LIDAR with a ``scan_seconds``): the largest
    sample count whose plan, in the sensor's own visiting order, scans within the time of the
    ``reference`` planner's plan at the same density
    (:func:`~simlunar.lidar.planning.fit_to_time`; searched over ``k / 4 .. 4 k``).
    ``budget`` (any plan-directed LIDAR): the largest sample count whose plan scans within
    ``budget_s`` seconds and fires at most ``budget_j`` joules of laser energy (either or
    both; :meth:`scan_seconds` / :meth:`scan_energy_j` of the sensor), whatever the density:
    sensors side by side at equal time or equal energy (searched from the density's count over
    ``3 .. N``, the guide's pixels; the density only names the row).
    ``receiver`` (micromirror flash): at most ``frames`` dots per receiver pixel. A map drawn
    by the paper's weighted random draw is drawn again under the cap, its map steering where
    (:func:`~simlunar.lidar.planning.receiver_capped_plan`); every other planner (a Lloyd
    placement, the grid, uniform Lloyd, ...) keeps its own layout and moves only the dots over
    the cap, each to the nearest free pixel of a receiver pixel with room
    (:func:`~simlunar.lidar.planning.receiver_capped_layout`).
    """

    kind: str = option(
        "scan_time",
        doc="scan_time: the most samples whose tour fits the reference planner's scan time at "
        "the same density; budget: the most within budget_s and / or budget_j; receiver "
        "(micromirror): at most `frames` dots per receiver pixel",
        choices=FITS,
    )
    reference: str = option(
        "grid", doc="scan_time: the planner label whose scan time is the budget (in the study)"
    )
    frames: int | None = option(
        None, doc="receiver: most dots per receiver pixel; None = the least that holds k", ge=1
    )
    budget_s: float | None = option(
        None, doc="budget: the scan's time budget; None = no time limit", unit="s", gt=0
    )
    budget_j: float | None = option(
        None, doc="budget: the laser energy budget; None = no energy limit", unit="J", gt=0
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        given = self.budget_s is not None or self.budget_j is not None
        if self.kind == "budget" and not given:
            raise ValueError("a budget fit needs budget_s, budget_j or both")
        if self.kind != "budget" and given:
            raise ValueError(f"budget_s / budget_j are for a budget fit, not {self.kind!r}")


def lidar_planners(o, image, depth, ks, *, sensor, guide=None) -> dict[str, Callable]:
    """Label -> protocol planner of a :class:`~simlunar.study.lidar.LidarStudyOptions` ``o``.

    Parameters
    ----------
    o : LidarStudyOptions
    image : ndarray (rows, cols[, 3])
        The guide image every image strategy reads.
    depth : ndarray float64 (rows, cols)
        The guide view's true z-depth (m): given to the oracles, and to nothing else.
    ks : sequence of int
        The planned pixel counts of the study's densities.
    sensor : Sensor
        The study's LIDAR (fits and multi-round planning read it).
    guide : Guide, optional
        What an oracle of a guided reconstruction reconstructs with.

    Raises
    ------
    ValueError
        An oracle on a guide view with pixels off the terrain, a multi-round planner on a
        sensor whose samples are not the planned cells or on a moving sensor without rounds
        that continue its trajectory, or a fit of a multi-round planner.
    """
    cache: dict = {}
    planners = {}
    for label in o.planners:
        base = o.strategies.get(label, label)
        opts = dict(o.planner_opts.get(label, {}))
        if base in MEASURING:
            _check_rounds(label, sensor, o.fits)
            m = measuring_planner(opts, image, depth.shape, ks, cache)
            planners[label] = LidarRounds(m.options, m.priors, m.shape)
            continue
        truth = recon = None
        if base in ORACLES:
            truth = _oracle_truth(label, depth)
            if "reconstruction" in opts:
                recons = reconstruction_options(o.reconstructions, outside=o.outside)
                recon = oracle_reconstruction(opts.pop("reconstruction"), recons, depth.shape,
                                              guide)  # fmt: skip
        planners[label] = _planner(base, image, opts, ks, cache, truth=truth, reconstruct=recon)
    for label, fit in o.fits.items():
        ref = planners.get(fit.reference)
        base = o.strategies.get(label, label)
        keep = _keeps_layout(base, o.planner_opts.get(label, {}))
        planners[label] = _fitted(fit, planners[label], ref, sensor, depth.shape, keep)
    return planners


def _keeps_layout(base: str, opts: Mapping) -> bool:
    """Whether a receiver fit keeps planner ``base``'s own layout
    (:func:`~simlunar.lidar.planning.receiver_capped_layout`): every planner but a map drawn
    by the paper's weighted random draw, which the receiver cap redraws inside each receiver
    pixel instead (:func:`~simlunar.lidar.planning.receiver_capped_plan`)."""
    if map_of(base) is None:
        return True
    return opts.get("placement", PLANNERS[base].target.placement) != "random"


def _oracle_truth(label: str, depth) -> np.ndarray:
    truth = np.asarray(depth, float)
    off = int((~np.isfinite(truth)).sum())
    if off:
        raise ValueError(
            f"{label!r}: an oracle reads the true depth of every guide pixel, but {off} "
            "pixels of the guide view miss the terrain"
        )
    return truth


def _check_rounds(label: str, sensor, fits: Mapping) -> None:
    if getattr(sensor, "name", "") == "flash":
        raise ValueError(
            f"{label!r}: a flash LIDAR measures its receiver pixels, not planned cells: "
            "multi-round planning needs a steered beam or a micromirror flash"
        )
    if getattr(getattr(sensor, "options", None), "motion", None) is not None and not hasattr(
        sensor, "rounds"
    ):
        raise ValueError(
            f"{label!r}: multi-round planning on a moving platform needs a sensor whose rounds "
            f"continue the platform's trajectory (the steered beam); {sensor.name!r} has none"
        )
    if label in fits:
        raise ValueError(f"fits[{label!r}]: a multi-round planner is not fitted to a sensor")


def _planner(base: str, image, opts: Mapping, ks, cache: dict, *, truth=None, reconstruct=None):
    """``(k, rng) -> rc`` of strategy ``base``; its map per k (the learned map's is per
    density, :func:`~simlunar.study.sampling_planners.importance_maps`), each computed once;
    ``truth`` (an oracle's true depth) and ``reconstruct`` (an oracle's reconstruction) go to
    :func:`~simlunar.planner.plan` as they are."""
    opts = dict(opts)
    maps = importance_maps(base, opts, image, ks, cache)
    rest = {k: v for k, v in opts.items() if k not in ("feature_opts", "coefficients")}
    if reconstruct is not None:
        rest["oracle_reconstruct"] = reconstruct
    if truth is not None:
        rest["truth"] = truth
    shape = image.shape[:2]
    plan(base, 3 if truth is None else 4, weights=maps[ks[0]], shape=shape, rng=0, **rest)

    def planner(k, rng):
        w = maps.get(int(k))
        if w is None:  # a fitted planner asks other counts: the nearest density's map
            w = maps[min(maps, key=lambda q: abs(np.log(q / max(int(k), 1))))]
        return plan(base, int(k), weights=w, shape=shape, rng=rng, **rest).rc

    planner.map = lambda k: maps[int(k)] if map_of(base) is not None else None
    return planner


def _fitted(fit, planner, reference, sensor, shape, keep_layout: bool = False) -> Callable:
    """A planner fitted to ``sensor`` (:class:`SensorFit`); a receiver
    fit with ``keep_layout`` moves the planner's own layout under the cap."""
    n = int(shape[0]) * int(shape[1])
    if fit.kind == "receiver":
        rx = tuple(sensor.options.receiver_px)
        if keep_layout:
            return lambda k, rng: receiver_capped_layout(
                planner(k, rng), shape=shape, receiver_shape=rx, frames=fit.frames
            )

        def capped(k, rng):
            return receiver_capped_plan(planner.map(k), int(k), shape=shape, receiver_shape=rx,
                                        frames=fit.frames, rng=rng)  # fmt: skip

        return capped
    if fit.kind == "budget":
        return _budgeted(fit, planner, sensor, n)
    if not hasattr(sensor, "scan_seconds"):
        raise ValueError(f"a scan-time fit needs a sensor with scan_seconds, not {sensor.name!r}")

    def timed(k, rng):
        budget = sensor.scan_seconds(reference(k, rng))
        rc, _ = fit_to_time(lambda q: planner(q, rng), sensor.scan_seconds, budget,
                            k_max=min(4 * int(k), n), k_min=max(1, int(k) // 4))  # fmt: skip
        return rc

    return timed


def budget_cost(fit, sensor) -> Callable[[np.ndarray], float]:
    """A plan's share of a budget fit's budget (<= 1 fits): the larger of its scan time over
    ``budget_s`` and its laser energy over ``budget_j`` (each where given)."""
    parts = [(fit.budget_s, "scan_seconds"), (fit.budget_j, "scan_energy_j")]
    parts = [(b, getattr(sensor, m, None), m) for b, m in parts if b is not None]
    for _, f, m in parts:
        if f is None:
            raise ValueError(f"a budget fit needs a sensor with {m}, not {sensor.name!r}")
    return lambda rc: max(f(rc) / b for b, f, _ in parts)


def _budgeted(fit, planner, sensor, n: int) -> Callable:
    """The planner at the most samples within ``fit``'s absolute budget
    (:func:`~simlunar.lidar.planning.fit_to_budget`, searched from the density's count); a
    budget too small for :data:`~simlunar.planner.strategies.MIN_K` samples gets that plan, over
    budget (its row's ``seconds`` and ``energy_j`` say by how much)."""
    cost = budget_cost(fit, sensor)

    def budgeted(k, rng):
        rc, _ = fit_to_budget(lambda q: planner(q, rng), cost, 1.0, k_start=int(k), k_max=n,
                              k_min=min(MIN_K, n))  # fmt: skip
        return rc

    return budgeted


def planned_values(acq: Acquisition, n: int) -> np.ndarray:
    """The measured z-depth (m) of each of the ``n`` planned cells of ``acq``, NaN where the
    sensor detected no return (``acq.detail.valid``: one flag per planned cell, in the plan's
    order; a sensor without a detail measured every cell)."""
    detail = getattr(acq, "detail", None)
    valid = np.ones(n, bool) if detail is None else np.asarray(detail.valid, bool).ravel()
    if valid.size != n or int(valid.sum()) != len(acq.values):
        raise ValueError(
            f"the acquisition's {valid.size} samples ({len(acq.values)} measured) are not the "
            f"{n} planned cells: multi-round planning needs one sample per planned cell"
        )
    out = np.full(n, np.nan)
    out[valid] = np.asarray(acq.values, float)
    return out


def _repoint_s(sensor, before: Acquisition, after: Acquisition) -> float:
    """Re-pointing (s) from the last pointing of ``before`` to the first of ``after``
    (``sensor.repoint_seconds``; 0 for a sensor without one: a micromirror switches)."""
    repoint = getattr(sensor, "repoint_seconds", None)
    if repoint is None or before.planned is None or after.planned is None:
        return 0.0
    last = np.asarray(before.detail.order).ravel()[-1]
    first = np.asarray(after.detail.order).ravel()[0]
    return float(repoint(before.planned[last], after.planned[first]))


def merge_rounds(acqs: list[Acquisition], sensor, *, gaps_s=None) -> Acquisition:
    """The rounds of a multi-round acquisition as one: samples of every round, in order;
    ``seconds`` the rounds' scan times plus the re-pointing between them (each round's own
    time already counts its tour and its lead); ``frames`` their sum; ``detail`` the rounds'
    scans joined (:func:`simlunar.lidar.join.join_scans`: times run on across rounds)
    where every round has a LIDAR scan.

    ``gaps_s`` (one per pair of rounds, s) is the re-pointing the sensor counted when it
    started each round (a moving platform's rounds,
    :class:`~simlunar.sensors.rounds.PlatformRounds`); None: priced here from the last planned
    cell of one round to the first of the next (``sensor.repoint_seconds``)."""
    if not acqs:
        raise ValueError("no round to merge")
    if gaps_s is None:
        gaps = [_repoint_s(sensor, a, b) for a, b in itertools.pairwise(acqs)]
    else:
        gaps = [float(g) for g in gaps_s]
        if len(gaps) != len(acqs) - 1:
            raise ValueError(f"need {len(acqs) - 1} re-pointing times, got {len(gaps)}")
    cat = np.concatenate
    planned = None
    if all(a.planned is not None for a in acqs):
        planned = cat([np.asarray(a.planned).reshape(-1, 2) for a in acqs])
    detail = None
    if all(a.detail is not None and hasattr(a.detail, "valid") for a in acqs):
        detail = join_scans([a.detail for a in acqs], gaps)
    return Acquisition(
        cat([np.asarray(a.rc, float).reshape(-1, 2) for a in acqs]),
        cat([np.asarray(a.values, float) for a in acqs]),
        acqs[0].shape,
        frames=int(sum(a.frames for a in acqs)),
        seconds=float(sum(a.seconds for a in acqs) + sum(gaps)),
        detail=detail,
        planned=planned,
        energy_j=float(sum(a.energy_j for a in acqs)),
    )


@dataclass(frozen=True, eq=False)
class LidarRounds(MeasuringPlanner):
    """Multi-round planning (:func:`simlunar.planner.plan_sequential`) with the LIDAR as its
    ``measure``: each round's planned cells are ranged by the sensor, its measured z-depths
    (NaN where no return was detected) steer the next round, and the result is every round's
    samples at the rounds' total time (:func:`merge_rounds`). The planner reads the scene
    through the sensor only.

    A sensor with a ``rounds(rng=)`` method (:meth:`~simlunar.sensors.lidar.SteeredBeam.rounds`)
    measures the rounds one after the other through it: on a moving platform each round
    continues the trajectory where the previous ended (plus the re-pointing), and a cell's
    measured z-depth is that of its beam's point placed by the sensor's navigation (which
    projects near, not exactly at, the planned cell). Any other sensor measures each round
    with ``acquire``.

    Attributes
    ----------
    options : SequentialOptions or None
    priors : dict k -> (rows, cols) map, or None
    shape : (rows, cols)
    """

    def acquire(self, k: int, sensor, plan_rng, sensor_rng) -> tuple[Acquisition, int]:
        """``(Acquisition of every round, rounds)`` of ``k`` planned cells."""
        gen = np.random.default_rng(sensor_rng)
        acqs: list[Acquisition] = []
        take = sensor.rounds(rng=gen) if hasattr(sensor, "rounds") else None

        def measure(rc):
            acq = sensor.acquire(rc, rng=gen) if take is None else take(rc)
            acqs.append(acq)
            return planned_values(acq, len(rc))

        sp = self.rounds(k, measure, plan_rng, missing="skip")
        return merge_rounds(acqs, sensor, gaps_s=getattr(take, "gaps_s", None)), sp.rounds
