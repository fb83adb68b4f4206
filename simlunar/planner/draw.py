"""The paper's weighted random draw: samples drawn without replacement with probability
proportional to the importance map (paper section 4.1), the ``random`` placement of
:data:`simlunar.planner.registry.PLACEMENTS`.

Options (:class:`RandomDrawOptions`): a mixture with uniform sampling, a regional density cap
and Poisson-disk-like (blue-noise) acceptance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.planner._bluenoise import poisson_accept
from simlunar.registry import Options, option

__all__ = ["RandomDrawOptions", "weighted_draw"]


@dataclass(frozen=True)
class RandomDrawOptions(Options):
    """Options of the paper's weighted random draw (the ``random`` placement)."""

    density_power: float | None = option(
        None, doc="power of the map; null = 1 (random) or 1/2 (lloyd)", gt=0
    )
    uniform_mix: float = option(
        0.0, doc="mixture with uniform; left out = 0 (random), 0.25 (lloyd)", ge=0, le=1
    )
    density_cap: float | None = option(
        None, doc="max regional density, a multiple of the mean; null = none", ge=1
    )
    cap_block: int = option(16, doc="block side of density_cap", unit="px", ge=1)
    blue_noise: bool = option(False, doc="Poisson-disk-like weighted sampling")
    blue_noise_radius: float = option(0.5, doc="radius factor of blue_noise", gt=0)


def weighted_draw(weights, k: int, *, rng, options: RandomDrawOptions) -> np.ndarray:
    """Draw ``k`` distinct pixels with probability proportional to ``weights`` (flat indices).

    Efraimidis-Spirakis priority keys (:func:`_priority_keys`) of the map raised to
    ``density_power`` and mixed with a ``uniform_mix`` share of uniform sampling; the k
    smallest keys, or those accepted by the density cap or the blue-noise test.

    Parameters
    ----------
    weights : ndarray, shape (rows, cols), >= 0
    k : int
    rng : numpy.random.Generator
    options : RandomDrawOptions

    Returns
    -------
    ndarray of int64, shape (k,)
        Flat (row-major) indices, unsorted.
    """
    w = weights.ravel()
    power = options.density_power
    # the paper's draw is proportional to the map: power 1 leaves its rng stream untouched
    if power is not None and power != 1:
        w = w**power
    return _weighted(k, weights.shape, w, rng, options)


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
    k: int, shape, w: np.ndarray, rng: np.random.Generator, draw: RandomDrawOptions
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
