"""Sampling strategies: choose k of the rows * cols pixels of the native grid.

Strategies (``STRATEGIES``): ``grid`` (N x M lattice shifted at random per call), ``random``
(uniform without replacement) and the feature-weighted ones ``gradient``, ``entropy``,
``wavelet``, ``saliency`` and ``combination`` (a linear combination of feature maps), which
draw without replacement with probability proportional to the map (paper section 4.1).

Options of the weighted strategies (keyword arguments of :func:`plan`):

``uniform_mix`` (float in [0, 1], default 0)
    Mixture with uniform sampling: weights (1 - m) w / sum(w) + m / N.
``density_cap`` (float >= 1, default None)
    Maximum regional density: no ``cap_block`` x ``cap_block`` block receives more than
    ceil(density_cap * (k / N) * block area) samples (a multiple of the mean density).
``cap_block`` (int, default 16)
    Block side in pixels for ``density_cap``.
``blue_noise`` (bool, default False)
    Poisson-disk-like weighted sampling: candidates in weighted-random priority order are
    accepted only if no accepted sample lies within r(p) = blue_noise_radius / sqrt(rho(p)),
    where rho(p) = k w(p) / sum(w) is the target local density (samples per pixel).
``blue_noise_radius`` (float > 0, default 0.5)
    The radius factor above (0.5 keeps clumps apart without starving dense regions).
``feature_opts`` (dict)
    Options for :func:`simlunar.features.feature_map` when the map is computed from ``image``.
``coefficients`` (dict name -> float)
    For ``combination``: the weight of each feature map (each map normalised to mean 1 first).
``placement`` (``"random"`` or ``"lloyd"``, default ``"random"``)
    How samples follow the map. ``"random"``: the paper's weighted random draw without
    replacement (paper parity; the options above). ``"lloyd"``: deterministic variable-density
    placement (:func:`simlunar.planner.placement.place`: error-diffusion halftone of the density,
    weighted Lloyd relaxation, border snapped, corners sampled); the density is
    :func:`~simlunar.planner.placement.density_from_map` of the map with ``density_power`` and
    ``uniform_mix``. ``density_cap`` and ``blue_noise`` apply to ``"random"`` only.
``density_power`` (float > 0, default 1 for ``"random"``, 0.5 for ``"lloyd"``)
    Exponent applied to the map before normalising.
``uniform_mix`` (float in [0, 1])
    Default for ``"lloyd"``: 0.25 (0 for ``"random"``).
``lloyd_iterations`` (int >= 0, default 20), ``border_pitch`` (float >= 0 or None, default 0.75)
    Lloyd iterations and border snap distance in local pitches (``"lloyd"`` placement,
    ``lloyd_uniform`` and ``oracle_hessian``).

Image-free layout (no map): ``lloyd_uniform`` places a uniform density with the ``"lloyd"``
placement (options ``lloyd_iterations``, ``border_pitch``): the fair image-free reference for the
image-directed ``"lloyd"`` layouts.

Oracles (:data:`ORACLES`, labels "Oracle ..."): they READ THE TRUE DEPTH, passed as
``plan(..., truth=depth)``, and can never be realised; they bound the headroom.
``oracle_greedy`` (options ``start_share`` 0.25, ``batch_share`` 0.15, ``smooth_pitch`` 0.25,
``nms_pitch`` 1, see
:func:`simlunar.planner.oracle.oracle_greedy`) and ``oracle_hessian`` (``density_power`` 0.5,
``uniform_mix`` 0.25, ``lloyd_iterations``, ``border_pitch``). No other strategy reads ``truth``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from simlunar.features import FEATURES, check_image, feature_map
from simlunar.planner._bluenoise import poisson_accept
from simlunar.planner.oracle import ORACLES, oracle_greedy, oracle_hessian
from simlunar.planner.placement import density_from_map, place
from simlunar.planner.types import SamplePlan

__all__ = [
    "COMBINABLE",
    "PLACEMENTS",
    "STRATEGIES",
    "STRATEGY_NAMES",
    "WEIGHTED",
    "check_k",
    "combination_map",
    "combine_maps",
    "normalised_map",
    "plan",
    "strategy_options",
    "strategy_weights",
]

WEIGHTED = ("gradient", "entropy", "wavelet", "saliency", "combination")
#: display names of the strategies (paper spelling), for tables and figure legends
STRATEGY_NAMES = {
    "random": "Random",
    "grid": "Grid",
    "gradient": "Gradient",
    "entropy": "Entropy",
    "wavelet": "Wavelet",
    "saliency": "Saliency",
    "combination": "Combination",
    "lloyd_uniform": "Uniform Lloyd (no image)",
    "oracle_greedy": "Oracle greedy (true error)",
    "oracle_hessian": "Oracle Hessian (true depth)",
    "sequential": "Sequential (multi-round)",
}
# ---- learned importance map (simlunar.features.learned): a weighted strategy whose
# map comes from a trained model: feature_opts={"model": "<name>.joblib", "density": k / N}
WEIGHTED += ("learned",)
STRATEGY_NAMES["learned"] = "Learned"
# ----
#: how weighted strategies place samples: the paper's weighted random draw, or halftone + Lloyd
PLACEMENTS = ("random", "lloyd")
_WEIGHTED_OPTS = (
    "uniform_mix",
    "density_cap",
    "cap_block",
    "blue_noise",
    "blue_noise_radius",
    "feature_opts",
    "coefficients",
    "placement",
    "density_power",
    "lloyd_iterations",
    "border_pitch",
)
_LLOYD_OPTS = ("lloyd_iterations", "border_pitch")
_RANDOM_ONLY = ("density_cap", "cap_block", "blue_noise", "blue_noise_radius")
#: options of the strategies that are not weighted (grid and random take none)
_OTHER_OPTS = {
    "lloyd_uniform": _LLOYD_OPTS,
    "oracle_greedy": ("start_share", "batch_share", "smooth_pitch", "nms_pitch"),
    "oracle_hessian": ("density_power", "uniform_mix", *_LLOYD_OPTS),
}


def strategy_options(strategy: str) -> tuple[str, ...]:
    """The option names :func:`plan` accepts for a strategy (for config validation)."""
    base = _resolve(strategy)
    return _WEIGHTED_OPTS if base in WEIGHTED else _OTHER_OPTS.get(base, ())


def check_k(k, n: int) -> int:
    """Validate the sample count against the number of pixels ``n``."""
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
        raise ValueError(f"k must be an integer, got {k!r}")
    k = int(k)
    if k < 3:
        raise ValueError(f"k must be >= 3 (a triangle needs three samples), got {k}")
    if k > n:
        raise ValueError(f"k = {k} exceeds the number of pixels N = {n}")
    return k


def normalised_map(m: np.ndarray) -> np.ndarray:
    """Map scaled to mean 1 (all zeros stays zeros)."""
    mean = float(m.mean())
    return m / mean if mean > 0 else np.zeros_like(m)


#: maps a combination may weight: ``uniform`` (a constant map) and the feature maps
COMBINABLE = ("uniform", *FEATURES)


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
    """The importance map a strategy samples from (None for ``grid`` and ``random``).

    This is the expensive part of a weighted plan; compute it once per image and pass it to
    :func:`plan` as ``weights=``.
    """
    base = _resolve(strategy)
    if base not in WEIGHTED:
        return None
    feature_opts = feature_opts or {}
    if base == "combination":
        if not coefficients:
            raise ValueError("strategy 'combination' needs coefficients={feature: weight}")
        maps = {n: combination_map(n, image, **feature_opts.get(n, {})) for n in coefficients}
        return combine_maps(maps, coefficients)
    return feature_map(base, image, **feature_opts)


def _resolve(strategy: str) -> str:
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown strategy {strategy!r}; valid: {', '.join(STRATEGIES)}")
    return strategy


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


def _priority_keys(w: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Efraimidis-Spirakis keys E / w (E ~ Exp(1)): the k smallest are a weighted sample
    without replacement (Efraimidis & Spirakis, Inf. Proc. Letters 97(5), 2006).

    Zero-weight pixels get keys above every positive-weight key, in random order, so they are
    only drawn (uniformly) once the positive-weight pixels are exhausted.
    """
    e = rng.standard_exponential(w.size)
    with np.errstate(divide="ignore", invalid="ignore"):
        keys = e / w
    zero = w == 0
    if zero.any():
        pos = ~zero
        top = keys[pos].max() if pos.any() else 0.0
        keys[zero] = 2.0 * top + 1.0 + e[zero]
    return keys


def _capped(keys: np.ndarray, k: int, shape, cap: float, block: int) -> np.ndarray:
    nr_px, nc_px = shape
    n = nr_px * nc_px
    per_block = int(np.ceil(cap * k / n * block * block))
    order = np.argsort(keys, kind="stable")
    r, c = np.divmod(order, nc_px)
    blocks = (r // block) * (-(-nc_px // block)) + c // block
    # rank of each candidate inside its block in priority order (greedy acceptance)
    by_block = np.argsort(blocks, kind="stable")
    sorted_blocks = blocks[by_block]
    starts = np.flatnonzero(np.r_[True, sorted_blocks[1:] != sorted_blocks[:-1]])
    first = np.repeat(starts, np.diff(np.r_[starts, n]))
    rank = np.empty(n, dtype=np.int64)
    rank[by_block] = np.arange(n) - first
    accepted = order[rank < per_block]
    if accepted.size < k:
        raise ValueError(
            f"density_cap={cap} with cap_block={block} leaves room for only {accepted.size} < k = {k} samples"
        )
    return accepted[:k]


@dataclass(frozen=True)
class _RandomDraw:
    """Options of the paper's weighted random draw (``placement="random"``; module docstring)."""

    uniform_mix: float = 0.0
    density_cap: float | None = None
    cap_block: int = 16
    blue_noise: bool = False
    blue_noise_radius: float = 0.5


def _mixed(w: np.ndarray, uniform_mix: float) -> np.ndarray:
    """The map as probabilities, mixed with a ``uniform_mix`` share of uniform sampling."""
    n = w.size
    if not 0.0 <= uniform_mix <= 1.0:
        raise ValueError(f"uniform_mix must be in [0, 1], got {uniform_mix}")
    total = float(w.sum())
    # Constant (or all-zero) maps carry no information: sample uniformly.
    if total <= 0 or float(w.max()) == float(w.min()):
        w = np.full(n, 1.0 / n)
    else:
        w = w / total
    if uniform_mix > 0:
        w = (1.0 - uniform_mix) * w + uniform_mix / n
    return w


def _blue_noise(keys: np.ndarray, k: int, shape, w: np.ndarray, radius_factor: float):
    if radius_factor <= 0:
        raise ValueError(f"blue_noise_radius must be > 0, got {radius_factor}")
    n = w.size
    m = min(n, 8 * k)
    cand = np.argpartition(keys, m - 1)[:m] if m < n else np.arange(n)
    cand = cand[np.argsort(keys[cand], kind="stable")]
    rho = np.maximum(k * w, 1e-12)
    # cap the radius at 4 lattice spacings so near-zero weights do not search the image
    radius = np.minimum(radius_factor / np.sqrt(rho), 4.0 * np.sqrt(n / k))
    return poisson_accept(cand, radius, np.asarray(shape, dtype=np.int64), k)


def _weighted(
    k: int, shape, w: np.ndarray, rng: np.random.Generator, draw: _RandomDraw
) -> np.ndarray:
    w = _mixed(w, draw.uniform_mix)
    keys = _priority_keys(w, rng)
    if draw.density_cap is not None:
        if draw.density_cap < 1 or draw.cap_block < 1:
            raise ValueError(
                "density_cap must be >= 1 and cap_block >= 1, "
                f"got {draw.density_cap}, {draw.cap_block}"
            )
        return _capped(keys, k, shape, float(draw.density_cap), int(draw.cap_block))
    if draw.blue_noise:
        return _blue_noise(keys, k, shape, w, draw.blue_noise_radius)
    if k == w.size:
        return np.arange(w.size)
    return np.argpartition(keys, k - 1)[:k]


def _grid_strategy(k, shape, weights, rng, **opts):
    return _grid(k, shape, rng)


def _random_strategy(k, shape, weights, rng, **opts):
    return rng.choice(shape[0] * shape[1], size=k, replace=False)


def _weighted_strategy(
    k, shape, weights, rng, *, placement="random", density_power=None, **opts
) -> np.ndarray:
    opts.pop("feature_opts", None)
    opts.pop("coefficients", None)
    if density_power is not None and not density_power > 0:
        raise ValueError(f"density_power must be > 0, got {density_power}")
    if placement == "random":
        lloyd_only = sorted(set(opts) & set(_LLOYD_OPTS))
        if lloyd_only:
            raise ValueError(f"option(s) {lloyd_only} need placement='lloyd'")
        w = weights.ravel()
        # the paper's draw is proportional to the map: power 1 leaves its rng stream untouched
        if density_power is not None and density_power != 1:
            w = w**density_power
        return _weighted(k, shape, w, rng, _RandomDraw(**opts))
    if placement == "lloyd":
        random_only = sorted(set(opts) & set(_RANDOM_ONLY))
        if random_only:
            raise ValueError(f"option(s) {random_only} apply to placement='random' only")
        return _lloyd_placed(
            k, weights, rng, power=0.5 if density_power is None else density_power, **opts
        )
    raise ValueError(f"unknown placement {placement!r}; valid: {', '.join(PLACEMENTS)}")


def _lloyd_placed(
    k, weights, rng, *, power, uniform_mix=0.25, lloyd_iterations=20, border_pitch=0.75
) -> np.ndarray:
    density = density_from_map(weights, power=power, mix=uniform_mix)
    return place(density, k, rng=rng, iterations=lloyd_iterations, border=border_pitch)


def _lloyd_uniform_strategy(k, shape, weights, rng, **opts):
    return _lloyd_placed(k, np.ones(shape), rng, power=1.0, uniform_mix=0.0, **opts)


#: plan option name -> keyword of the oracle function
_ORACLE_KEYS = {
    "start_share": "start",
    "batch_share": "batch",
    "smooth_pitch": "smooth",
    "nms_pitch": "window",
    "density_power": "power",
    "uniform_mix": "mix",
    "lloyd_iterations": "iterations",
    "border_pitch": "border",
}


def _oracle_greedy_strategy(k, shape, weights, rng, *, truth, reconstruct=None, **opts):
    kw = {_ORACLE_KEYS[n]: v for n, v in opts.items()}
    return oracle_greedy(truth, k, rng=rng, reconstruct=reconstruct, **kw)


def _oracle_hessian_strategy(k, shape, weights, rng, *, truth, **opts):
    return oracle_hessian(truth, k, rng=rng, **{_ORACLE_KEYS[n]: v for n, v in opts.items()})


STRATEGIES: dict[str, Callable[..., np.ndarray]] = {
    "grid": _grid_strategy,
    "random": _random_strategy,
    **{name: _weighted_strategy for name in WEIGHTED},
    "lloyd_uniform": _lloyd_uniform_strategy,
    "oracle_greedy": _oracle_greedy_strategy,
    "oracle_hessian": _oracle_hessian_strategy,
}


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
        One of ``STRATEGIES``.
    k : int
        Number of samples, 3 <= k <= rows * cols.
    image : ndarray, shape (rows, cols) or (rows, cols, 3), optional
        Guide image; weighted strategies compute their map from it unless ``weights`` is given.
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
        Strategy options, see the module docstring.

    Returns
    -------
    SamplePlan
        Exactly k distinct in-bounds pixels, in row-major order.
    """
    base = _resolve(strategy)
    rng = np.random.default_rng(rng)
    allowed = strategy_options(base)
    bad = sorted(set(opts) - set(allowed))
    if bad:
        raise ValueError(
            f"unknown option(s) {bad} for strategy {strategy!r}; valid: {', '.join(allowed) or 'none'}"
        )
    grid_shape, image, weights, truth = _grid_inputs(image, weights, shape, truth)
    if base in ORACLES:
        if truth is None:
            raise ValueError(
                f"strategy {strategy!r} is an oracle: it needs truth= (the true depth)"
            )
        opts["truth"] = truth
    if oracle_reconstruct is not None:
        if base != "oracle_greedy":
            raise ValueError(
                f"oracle_reconstruct is an option of oracle_greedy only, not of {strategy!r}"
            )
        opts["reconstruct"] = oracle_reconstruct
    k = check_k(k, grid_shape[0] * grid_shape[1])
    if base in WEIGHTED and weights is None:
        if image is None:
            raise ValueError(f"strategy {strategy!r} needs image= or weights=")
        weights = strategy_weights(
            base,
            image,
            feature_opts=opts.get("feature_opts"),
            coefficients=opts.get("coefficients"),
        )
    flat = STRATEGIES[base](k, grid_shape, weights, rng, **opts)
    # canonical row-major order: plans compare as sets, and sorted samples keep the
    # reconstruction's memory access coherent
    return SamplePlan.from_flat(np.sort(flat), grid_shape)
