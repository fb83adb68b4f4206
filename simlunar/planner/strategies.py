"""Sampling strategies: choose k of the rows * cols pixels of the native grid.

Every strategy is an entry of :data:`simlunar.planner.registry.PLANNERS` (registered by
:mod:`simlunar.planner`) with its options class; :func:`plan` runs one by name and checks its
options against the entry:

- ``grid`` (N x M lattice shifted at random per call) and ``random`` (uniform without
  replacement) take no options.
- *Map planners* sample an importance map (a :data:`simlunar.features.MAPS` entry: every map
  is a planner of its own name, the paper's strategies of section 4.1, plus named variants
  such as ``wavelet_lloyd``) or the ``combination`` of maps (``coefficients``: map -> weight,
  each map normalised to mean 1). Options: ``feature_opts`` (the map's options class),
  ``placement`` (``"random"``: the paper's weighted random draw without replacement,
  :class:`~simlunar.planner.draw.RandomDrawOptions`; ``"lloyd"``: error-diffusion halftone +
  weighted Lloyd with the border covered, :class:`~simlunar.planner.placement.LloydOptions`)
  and the options of that placement.
- ``lloyd_uniform``: the ``lloyd`` layout of a uniform density (:class:`UniformLloydOptions`),
  the fair image-free reference of the image-directed ``lloyd`` layouts.
- Oracles (:data:`~simlunar.planner.oracle.ORACLES`, labels "Oracle ..."): they READ THE TRUE
  DEPTH, passed as ``plan(..., truth=depth)``, and can never be realised; they bound the
  headroom. ``oracle_greedy`` (:class:`~simlunar.planner.oracle.OracleGreedyOptions`, see
  :func:`simlunar.planner.oracle.oracle_greedy`) and ``oracle_hessian``
  (:class:`~simlunar.planner.oracle.OracleHessianOptions`). No other strategy reads ``truth``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.features import check_image, feature_map
from simlunar.planner.oracle import (
    OracleGreedyOptions,
    OracleHessianOptions,
    oracle_greedy,
    oracle_hessian,
)
from simlunar.planner.placement import LloydOptions, lloyd_layout
from simlunar.planner.registry import (
    COMBINATION,
    PLACEMENTS,
    PLANNERS,
    MapSource,
    combinable,
    field_names,
    planner_options,
)
from simlunar.planner.types import SamplePlan
from simlunar.registry import Options, UnknownNameError, did_you_mean, option

__all__ = [
    "COMBINABLE",
    "STRATEGIES",
    "UniformLloydOptions",
    "check_k",
    "combination_map",
    "combine_maps",
    "grid_planner",
    "lloyd_uniform_planner",
    "map_plan_options",
    "normalised_map",
    "oracle_greedy_planner",
    "oracle_hessian_planner",
    "plan",
    "random_planner",
    "strategy_options",
    "strategy_weights",
]

#: every strategy: a view of :data:`simlunar.planner.registry.PLANNERS`
STRATEGIES = PLANNERS


def strategy_options(strategy: str) -> tuple[str, ...]:
    """The option names :func:`plan` accepts for a strategy (for config validation)."""
    return planner_options(strategy)


#: the fewest samples of a plan (a triangle: the least a reconstruction interpolates)
MIN_K = 3


def check_k(k, n: int) -> int:
    """Validate the sample count against the number of pixels ``n``."""
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
        raise ValueError(f"k must be an integer, got {k!r}")
    k = int(k)
    if k < MIN_K:
        raise ValueError(f"k must be >= {MIN_K} (a triangle needs three samples), got {k}")
    if k > n:
        raise ValueError(f"k = {k} exceeds the number of pixels N = {n}")
    return k


def normalised_map(m: np.ndarray) -> np.ndarray:
    """Map scaled to mean 1 (all zeros stays zeros)."""
    mean = float(m.mean())
    return m / mean if mean > 0 else np.zeros_like(m)


#: maps a combination may weight: ``uniform`` (a constant map) and the paper's feature maps
COMBINABLE = combinable()


def combination_map(name: str, image, **opts) -> np.ndarray:
    """A map of :data:`COMBINABLE`: ones for ``uniform``, else ``feature_map(name, image)``."""
    if name == "uniform":
        return np.ones(check_image(image).shape[:2])
    return feature_map(name, image, **opts)


def combine_maps(maps: dict[str, np.ndarray], coefficients: dict[str, float]) -> np.ndarray:
    """Linear combination sum_i |a_i| m_i / mean(m_i) of feature maps.

    Absolute values keep the weights non-negative whatever the optimiser proposes. Names are
    those of :data:`COMBINABLE` (``uniform`` is a constant map, i.e. a uniform-sampling share).
    """
    unknown = sorted(set(coefficients) - set(COMBINABLE))
    if unknown:
        raise ValueError(
            f"unknown feature(s) {unknown} in coefficients; valid: {', '.join(COMBINABLE)}"
        )
    if not coefficients:
        raise ValueError("coefficients must name at least one feature map")
    shape = next(iter(maps.values())).shape
    total = np.zeros(shape)
    for name, a in coefficients.items():
        total += abs(float(a)) * normalised_map(maps[name])
    return total


def strategy_weights(
    strategy: str, image, *, feature_opts: dict | None = None, coefficients: dict | None = None
) -> np.ndarray | None:
    """The importance map a strategy samples from (None for a strategy without a map).

    This is the expensive part of a map planner's plan; compute it once per image and pass
    it to :func:`plan` as ``weights=``.
    """
    source = PLANNERS[strategy].target
    if not isinstance(source, MapSource):
        return None
    feature_opts = feature_opts or {}
    if source.map == COMBINATION:
        if not coefficients:
            raise ValueError(f"strategy {strategy!r} needs coefficients={{feature: weight}}")
        maps = {n: combination_map(n, image, **feature_opts.get(n, {})) for n in coefficients}
        return combine_maps(maps, coefficients)
    return feature_map(source.map, image, **feature_opts)


def _grid(k: int, shape, rng: np.random.Generator) -> np.ndarray:
    """n_r x n_c lattice (n_r n_c >= k, aspect ~ the grid's) with a random sub-cell shift.

    Lattice positions floor(offset + i * pitch) with pitch = rows / n_r >= 1 are distinct; the
    n_r n_c - k surplus points (fewer than one lattice row or column) are dropped at random.
    """
    nr_px, nc_px = shape
    n_r = int(np.clip(round(np.sqrt(k * nr_px / nc_px)), 1, nr_px))
    n_c = -(-k // n_r)
    if n_c > nc_px:
        n_c = nc_px
        n_r = -(-k // nc_px)
    pitch_r, pitch_c = nr_px / n_r, nc_px / n_c
    off_r, off_c = rng.uniform(0.0, pitch_r), rng.uniform(0.0, pitch_c)
    rows = np.minimum(np.floor(off_r + pitch_r * np.arange(n_r)).astype(np.int64), nr_px - 1)
    cols = np.minimum(np.floor(off_c + pitch_c * np.arange(n_c)).astype(np.int64), nc_px - 1)
    flat = (rows[:, None] * nc_px + cols[None, :]).ravel()
    if flat.size > k:
        flat = np.delete(flat, rng.choice(flat.size, flat.size - k, replace=False))
    return flat


# ---- the function planners: fn(k, shape, rng, *, truth, options) -> flat indices ------------


def grid_planner(k, shape, rng, *, truth=None, options=None) -> np.ndarray:
    """A lattice of k points shifted at random (:func:`_grid`)."""
    return _grid(k, shape, rng)


def random_planner(k, shape, rng, *, truth=None, options=None) -> np.ndarray:
    """k pixels uniformly at random without replacement."""
    return rng.choice(shape[0] * shape[1], size=k, replace=False)


@dataclass(frozen=True)
class UniformLloydOptions(Options):
    """Options of ``lloyd_uniform``: the ``lloyd`` layout of a uniform density."""

    lloyd_iterations: int = option(20, doc="lloyd: relaxation steps", ge=0, le=1000)
    border_pitch: float | None = option(
        0.75, doc="lloyd: snap samples this many pitches from the border onto it", ge=0
    )


def lloyd_uniform_planner(k, shape, rng, *, truth=None, options: UniformLloydOptions):
    """The ``lloyd`` placement of a constant map (density power 1, no uniform share)."""
    o = LloydOptions(1.0, 0.0, options.lloyd_iterations, options.border_pitch)
    return lloyd_layout(np.ones(shape), k, rng=rng, options=o)


def oracle_greedy_planner(k, shape, rng, *, truth, options: OracleGreedyOptions, reconstruct=None):
    o = options
    if reconstruct is None and o.reconstruction != "linear":
        raise ValueError(
            f"oracle_greedy: reconstruction {o.reconstruction!r} needs its reconstruction "
            "given to plan() as oracle_reconstruct=(rc, values) -> heights"
        )
    return oracle_greedy(truth, k, rng=rng, options=o, reconstruct=reconstruct)


def oracle_hessian_planner(k, shape, rng, *, truth, options: OracleHessianOptions):
    return oracle_hessian(truth, k, rng=rng, options=options)


def _grid_inputs(image, weights, shape, truth):
    """Validated inputs and the one grid shape they agree on."""
    shapes = {}
    if image is not None:
        image = check_image(image)
        shapes["image"] = image.shape[:2]
    if weights is not None:
        weights = np.asarray(weights, dtype=np.float64)
        if weights.ndim != 2:
            raise ValueError(f"weights must have shape (rows, cols), got {weights.shape}")
        if not np.all(np.isfinite(weights)) or weights.min() < 0:
            raise ValueError("weights must be finite and >= 0")
        shapes["weights"] = weights.shape
    if shape is not None:
        shapes["shape"] = tuple(int(s) for s in shape)
    if truth is not None:
        truth = np.asarray(truth, dtype=np.float64)
        shapes["truth"] = truth.shape
    if not shapes:
        raise ValueError("plan needs one of image, weights or shape to know the grid")
    if len(set(shapes.values())) > 1:
        raise ValueError(f"mismatched grid shapes: {shapes}")
    grid_shape = next(iter(shapes.values()))
    if len(grid_shape) != 2 or min(grid_shape) < 1:
        raise ValueError(f"shape must be (rows, cols) > 0, got {grid_shape}")
    return grid_shape, image, weights, truth


def _entry(strategy):
    entry = PLANNERS[strategy]
    if entry.meta.get("measuring"):
        raise ValueError(
            f"strategy {strategy!r} measures while it plans: run it with plan_sequential"
        )
    return entry


def _check_keys(strategy: str, opts, allowed) -> None:
    bad = sorted(set(opts) - set(allowed))
    if bad:
        raise UnknownNameError(
            f"unknown option(s) {bad} for strategy {strategy!r}; valid: "
            f"{', '.join(allowed) or 'none'}{did_you_mean(bad[0], allowed)}"
        )


def map_plan_options(strategy: str, opts: dict):
    """Split and check the options of map planner ``strategy`` as :func:`plan` takes them.

    Returns
    -------
    placement : str
    place_options : the placement's options object
    feature_opts : dict or None
    coefficients : dict or None
    """
    source: MapSource = PLANNERS[strategy].target
    _check_keys(strategy, opts, planner_options(strategy))
    rest = dict(opts)
    placement = rest.pop("placement", source.placement)
    place = PLACEMENTS[placement]
    feature_opts = rest.pop("feature_opts", None)
    coefficients = rest.pop("coefficients", None)
    mine = field_names(place.options)
    other = sorted(k for k in rest if k not in mine)
    if other:
        need = next(p for p in PLACEMENTS if other[0] in field_names(PLACEMENTS[p].options))
        raise ValueError(f"option(s) {other} need placement={need!r} (not {placement!r})")
    return placement, place.make_options(rest), feature_opts, coefficients


def plan(
    strategy: str,
    k: int,
    *,
    image=None,
    weights=None,
    shape=None,
    truth=None,
    rng,
    oracle_reconstruct=None,
    **opts,
) -> SamplePlan:
    """Choose ``k`` distinct pixels with the named strategy.

    Parameters
    ----------
    strategy : str
        A name of :data:`STRATEGIES` (:data:`simlunar.planner.registry.PLANNERS`).
    k : int
        Number of samples, 3 <= k <= rows * cols.
    image : ndarray, shape (rows, cols) or (rows, cols, 3), optional
        Guide image; map planners compute their map from it unless ``weights`` is given.
    weights : ndarray, shape (rows, cols), optional
        Precomputed importance map (>= 0, finite), e.g. from :func:`strategy_weights`.
    shape : tuple of int, optional
        Grid shape when neither image nor weights is given (grid and random).
    truth : ndarray, shape (rows, cols), optional
        True depth, required by the ``oracle_*`` strategies and read by no other.
    rng : None, int, SeedSequence or Generator
        Randomness (the grid shift, the draws).
    oracle_reconstruct : callable, optional
        ``oracle_greedy`` only: ``(rc, values) -> heights``, the reconstruction whose true
        error the oracle feeds back (default Delaunay-linear;
        :func:`simlunar.planner.oracle.oracle_greedy`).
    **opts
        The strategy's options (:func:`strategy_options`; module docstring): a stray key is a
        ``ValueError`` naming the valid ones.

    Returns
    -------
    SamplePlan
        Exactly k distinct in-bounds pixels, in row-major order.
    """
    entry = _entry(strategy)
    if oracle_reconstruct is not None and strategy != "oracle_greedy":
        raise ValueError(
            f"oracle_reconstruct is an option of oracle_greedy only, not of {strategy!r}"
        )
    rng = np.random.default_rng(rng)
    source = entry.target
    if isinstance(source, MapSource):
        placement, place_opts, feature_opts, coefficients = map_plan_options(strategy, opts)
    else:
        _check_keys(strategy, opts, field_names(entry.options))
        options = entry.make_options(opts)
    grid_shape, image, weights, truth = _grid_inputs(image, weights, shape, truth)
    if entry.meta.get("truth") and truth is None:
        raise ValueError(f"strategy {strategy!r} is an oracle: it needs truth= (the true depth)")
    k = check_k(k, grid_shape[0] * grid_shape[1])
    if isinstance(source, MapSource):
        if weights is None:
            if image is None:
                raise ValueError(f"strategy {strategy!r} needs image= or weights=")
            weights = strategy_weights(
                strategy, image, feature_opts=feature_opts, coefficients=coefficients
            )
        flat = PLACEMENTS[placement].target(weights, k, rng=rng, options=place_opts)
    else:
        extra = {} if oracle_reconstruct is None else {"reconstruct": oracle_reconstruct}
        flat = source(k, grid_shape, rng, truth=truth if entry.meta.get("truth") else None,
                      options=options, **extra)  # fmt: skip
    # canonical row-major order: plans compare as sets, and sorted samples keep the
    # reconstruction's memory access coherent
    return SamplePlan.from_flat(np.sort(flat), grid_shape)
