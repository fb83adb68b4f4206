"""The sampling study's planners: each strategy label of a study as the protocol's planner.

A label names a strategy of :func:`simlunar.planner.plan` (with its options) or a measuring one
(:func:`simlunar.planner.plan_sequential`). Every distinct importance map is computed once per
study and shared across densities and trials; only the ``oracle_*`` labels get the true depth,
and the multi-round planner reads the scene through the sensor only, round by round. An
``oracle_greedy`` label whose options name a ``reconstruction`` (one of the study's, e.g.
``shading``) feeds back that reconstruction's true error, computed with the study's guide: the
bound of sampling for that fused model.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from simlunar.features import MAPS
from simlunar.planner import (
    MEASURING,
    ORACLES,
    STRATEGIES,
    map_of,
    plan,
    plan_sequential,
    strategy_weights,
)
from simlunar.reconstruction import run_reconstruction
from simlunar.sensors.base import Acquisition
from simlunar.study.protocol import (
    DEFAULT_RECONSTRUCTION,
    reconstruction_of,
    reconstruction_options,
)

__all__ = [
    "MapPlanner",
    "MeasuringPlanner",
    "OracleReconstruction",
    "importance_maps",
    "measuring_planner",
    "oracle_reconstruction",
    "study_planners",
]


@dataclass(frozen=True, eq=False)
class OracleReconstruction:
    """``(rc, values) -> heights``: the reconstruction ``name`` of a study (its options, the
    study's guide) on a grid of ``shape``: what an oracle of that reconstruction reads."""

    name: str
    options: object
    shape: tuple
    guide: object = None

    def __call__(self, rc, values) -> np.ndarray:
        base = reconstruction_of(self.options)
        return run_reconstruction(
            base, rc, values, self.shape, guide=self.guide, options=self.options
        ).heights


def oracle_reconstruction(name, reconstructions: Mapping, shape, guide=None):
    """The :class:`OracleReconstruction` of label ``name`` among a study's reconstructions
    (``name -> options``, :func:`simlunar.study.protocol.reconstruction_options`); None for
    ``linear``: the oracle's own Delaunay-linear (nearest sample outside the hull, whatever
    the study's ``outside``: a NaN outside the hull is no error to feed back), as before.

    Raises
    ------
    ValueError
        ``name`` is not ``linear`` nor one of the study's reconstructions.
    """
    if name == DEFAULT_RECONSTRUCTION:
        return None
    if name not in reconstructions:
        raise ValueError(
            f"an oracle's reconstruction {name!r} is not one of the study's reconstructions "
            f"({', '.join(reconstructions)})"
        )
    return OracleReconstruction(str(name), reconstructions[name], tuple(shape), guide)


def study_planners(o, image, depth, ks, *, guide=None) -> tuple[dict, dict]:
    """Label -> protocol planner of a :class:`~simlunar.study.sampling.SamplingStudyOptions`
    ``o`` (and the importance-map cache); each distinct importance map computed once.

    Only the ``oracle_*`` labels get the true depth; ``sequential`` gets the sensor (through
    the protocol), never the depth. An ``oracle_greedy`` label's option ``reconstruction``
    (a label of ``o.reconstructions``) names the reconstruction whose true error it reads
    (with ``guide``, the study's :class:`~simlunar.reconstruction.Guide`).
    """
    planners, maps_cache = {}, {}
    for label in o.strategies:
        opts = dict(o.strategy_options.get(label, {}))
        base = opts.pop("strategy", label)
        recon_fn = None
        if base == "oracle_greedy" and "reconstruction" in opts:
            recons = reconstruction_options(o.reconstructions, outside=o.outside)
            recon_fn = oracle_reconstruction(opts.pop("reconstruction"), recons, depth.shape,
                                             guide)  # fmt: skip
        if base not in STRATEGIES and base not in MEASURING:
            valid = ", ".join([*STRATEGIES, *MEASURING])
            raise ValueError(f"unknown strategy {base!r}; valid: {valid}")
        if base in MEASURING:
            planners[label] = measuring_planner(opts, image, depth.shape, ks, maps_cache)
            continue
        weights = importance_maps(base, opts, image, ks, maps_cache)
        plan_opts = {k: v for k, v in opts.items() if k not in ("feature_opts", "coefficients")}
        truth = depth if base in ORACLES else None  # the oracles, and nothing else, read it
        # validate options once, before any long loop
        plan(base, 4, weights=weights[ks[0]], shape=depth.shape, truth=truth, rng=0, **plan_opts)
        planners[label] = MapPlanner(base, weights, depth.shape, plan_opts, truth, recon_fn)
    return planners, maps_cache


def importance_maps(base: str, opts: dict, image, ks, cache: dict) -> dict:
    """k -> the strategy's importance map (one map for every k but a trained model's, which
    is per density)."""
    fo = opts.get("feature_opts")
    n = image.shape[0] * image.shape[1]
    source = map_of(base)
    per_density = source in MAPS and MAPS[source].meta.get("needs_model")
    out = {}
    for k in ks:
        if per_density:
            fo = {**(opts.get("feature_opts") or {}), "density": k / n}
        key = (source, repr(fo), repr(opts.get("coefficients")))
        if key not in cache:
            cache[key] = strategy_weights(
                base, image, feature_opts=fo, coefficients=opts.get("coefficients")
            )
        out[k] = cache[key]
    return out


def measuring_planner(opts: dict, image, shape, ks, cache: dict) -> MeasuringPlanner:
    prior = opts.get("prior")
    maps = None
    if prior is not None:
        maps = importance_maps(prior, {"feature_opts": opts.get("feature_opts")}, image, ks, cache)
    return MeasuringPlanner(opts.get("sequential"), maps, tuple(shape))


@dataclass(frozen=True, eq=False)
class MapPlanner:
    """A strategy of :func:`simlunar.planner.plan` with its map(s): ``(k, rng) -> (k, 2) rc``.

    ``truth`` is the true depth for an oracle strategy and None for every other;
    ``reconstruct`` the reconstruction an ``oracle_greedy`` reads the error of (None: linear).
    """

    base: str
    weights: dict
    shape: tuple
    opts: dict
    truth: np.ndarray | None = None
    reconstruct: object = None

    def __call__(self, k: int, rng) -> np.ndarray:
        return plan(
            self.base, k, weights=self.weights[k], shape=self.shape, truth=self.truth, rng=rng,
            oracle_reconstruct=self.reconstruct, **self.opts,
        ).rc  # fmt: skip


@dataclass(frozen=True, eq=False)
class MeasuringPlanner:
    """Region-based iterative enhancement (:func:`simlunar.planner.plan_sequential`): the
    sensor's ``acquire`` is its ``measure``, so it reads the scene at the cells it samples
    only, round by round."""

    options: object
    priors: dict | None
    shape: tuple
    measures = True

    def acquire(self, k: int, sensor, plan_rng, sensor_rng) -> tuple[Acquisition, int]:
        gen = np.random.default_rng(sensor_rng)
        cost = [0, 0.0, 0.0]

        def measure(rc):
            acq = sensor.acquire(rc, rng=gen)
            if len(acq.values) != len(rc):
                raise ValueError(f"sensor {sensor.name!r} lost cells: multi-round needs all")
            cost[0] += acq.frames
            cost[1] += acq.seconds
            cost[2] += acq.energy_j
            return acq.values

        sp = self.rounds(k, measure, plan_rng)
        acq = Acquisition(sp.plan.rc, np.asarray(sp.values), self.shape, cost[0], cost[1],
                          energy_j=cost[2])  # fmt: skip
        return acq, sp.rounds

    def rounds(self, k: int, measure, plan_rng, *, missing: str = "raise"):
        """:func:`~simlunar.planner.plan_sequential` of ``k`` cells with this planner's
        options and its prior at ``k``, reading the scene through ``measure`` only."""
        prior = None if self.priors is None else self.priors[k]
        return plan_sequential(k, shape=self.shape, measure=measure, prior=prior,
                               options=self.options, rng=plan_rng, missing=missing)  # fmt: skip
