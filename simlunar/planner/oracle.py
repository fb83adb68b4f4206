"""Oracle planners: they READ THE TRUE DEPTH, so no sensor can realise them.

They bound what any planner could gain and are labelled "Oracle ..." in every table:

- :func:`oracle_greedy`: error feedback on the truth. A framed grid of ``start_share`` k samples
  (the image border rows and columns included), then batches of about ``batch_share`` (15 %) more
  samples at the non-maximum-suppressed peaks of the smoothed true squared error of the current
  reconstruction (Delaunay-linear, or the one given as ``reconstruct``: an oracle for a fused,
  image-anchored model reads that model's error), until exactly k.
- :func:`oracle_hessian`: the true depth's Hessian norm |H|^p as the density, placed by
  :func:`simlunar.planner.placement.place` (halftone + weighted Lloyd with the border covered).

Both take the truth as an array and their options (:class:`OracleGreedyOptions`,
:class:`OracleHessianOptions`); through :func:`simlunar.planner.plan` they are the strategies
``oracle_greedy`` and ``oracle_hessian`` and need ``truth=``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from simlunar.planner.placement import density_from_map, place
from simlunar.reconstruction import reconstruct as _linear
from simlunar.registry import Options, option

__all__ = [
    "ORACLES",
    "OracleGreedyOptions",
    "OracleHessianOptions",
    "framed_grid",
    "hessian_norm",
    "oracle_greedy",
    "oracle_hessian",
]

#: the oracle strategies (read the truth; never realisable)
ORACLES = ("oracle_greedy", "oracle_hessian")


@dataclass(frozen=True)
class OracleGreedyOptions(Options):
    """``oracle_greedy``: the truth-driven refiner's schedule (:func:`oracle_greedy`; YAML
    section ``oracle``)."""

    start_share: float = option(
        0.25,
        doc="share of k in the initial framed grid (the image border rows and columns included)",
        gt=0,
        le=1,
    )
    batch_share: float = option(0.15, doc="batch, a share of the current count", gt=0)
    smooth_pitch: float = option(
        0.25,
        doc="Gaussian sigma of the squared-error smoothing, in current pitches sqrt(N / n)",
        ge=0,
    )
    nms_pitch: float = option(
        1.0,
        doc="non-maximum suppression window, in current pitches (odd, >= 3 cells): a batch "
        "takes the highest local maxima of the smoothed error within it",
        gt=0,
    )
    reconstruction: str = option(
        "linear",
        doc="whose true error the oracle feeds back: linear (the paper's) or a name or label "
        "of study.reconstructions (e.g. shading: the bound for the fused model); a study "
        "passes that reconstruction to plan() as oracle_reconstruct",
    )

    def __post_init__(self):
        super().__post_init__()
        if not self.reconstruction:
            raise ValueError("reconstruction: must name a reconstruction, got ''")


@dataclass(frozen=True)
class OracleHessianOptions(Options):
    """``oracle_hessian``: the true depth's Hessian density placed by halftone + Lloyd
    (:func:`oracle_hessian`; the density as :func:`~simlunar.planner.placement.density_from_map`,
    the placement as :func:`~simlunar.planner.placement.place`)."""

    density_power: float = option(0.5, doc="power of the Hessian norm", gt=0)
    uniform_mix: float = option(0.25, doc="mixture with uniform", ge=0, le=1)
    lloyd_iterations: int = option(20, doc="lloyd: relaxation steps", ge=0, le=1000)
    border_pitch: float | None = option(
        0.75, doc="lloyd: snap samples this many pitches from the border onto it", ge=0
    )


def _check_truth(truth, k) -> np.ndarray:
    truth = np.asarray(truth, dtype=np.float64)
    if truth.ndim != 2 or min(truth.shape) < 2:
        raise ValueError(
            f"truth must be a (rows, cols) depth map, rows, cols >= 2; got {truth.shape}"
        )
    if not np.all(np.isfinite(truth)):
        raise ValueError("truth contains NaN or infinite values")
    if not 4 <= k <= truth.size:
        raise ValueError(f"k = {k} must be in [4, {truth.size}] for an oracle")
    return truth


def framed_grid(shape, k: int) -> np.ndarray:
    """A lattice of at most k cells whose outer rows and columns lie on the image border.

    Parameters
    ----------
    shape : tuple of int
        Grid (rows, cols), each >= 2.
    k : int
        Sample budget, >= 4.

    Returns
    -------
    ndarray of int64, shape (n_r * n_c,)
        Sorted flat indices, n_r n_c <= k, n_r, n_c >= 2, aspect close to the grid's.
    """
    nr, nc = int(shape[0]), int(shape[1])
    n_r = int(np.clip(np.floor(np.sqrt(k * nr / nc)), 2, nr))
    n_c = int(np.clip(k // n_r, 2, nc))
    n_r = int(np.clip(min(n_r, k // n_c), 2, nr))
    rows = np.unique(np.rint(np.linspace(0, nr - 1, n_r)).astype(np.int64))
    cols = np.unique(np.rint(np.linspace(0, nc - 1, n_c)).astype(np.int64))
    return np.sort((rows[:, None] * nc + cols[None, :]).ravel())


def _batch(score, sampled, m, window) -> np.ndarray:
    """The m unsampled cells of highest score, peaks of a ``window``-wide maximum filter first."""
    peaks = (score == ndimage.maximum_filter(score, size=window, mode="nearest")).ravel()
    peaks &= ~sampled
    cand = np.flatnonzero(peaks)
    flat = score.ravel()
    if cand.size < m:  # too few peaks: the best of the remaining cells
        rest = np.flatnonzero(~sampled & ~peaks)
        top = rest[np.argpartition(-flat[rest], m - cand.size - 1)[: m - cand.size]]
        return np.concatenate((cand, top))
    return cand[np.argpartition(-flat[cand], m - 1)[:m]]


def oracle_greedy(
    truth, k: int, *, rng=None, options: OracleGreedyOptions | None = None, reconstruct=None
) -> np.ndarray:
    """Greedy error-feedback refiner on the true depth (an oracle bound, never realisable).

    Parameters
    ----------
    truth : array_like, shape (rows, cols)
        True depth (finite), read everywhere.
    k : int
        Number of samples, 4 <= k <= rows * cols.
    rng : None, int, SeedSequence or Generator
        Unused: the refiner is deterministic given the truth (accepted for the planner interface).
    options : OracleGreedyOptions, optional
        The schedule (initial share, batch, smoothing, suppression window); its
        ``reconstruction`` names what ``reconstruct`` computes and is not read here.
    reconstruct : callable, optional
        ``reconstruct(rc, values) -> heights``: rc (n, 2) int64 (row, col) of the current
        samples, values (n,) the truth there, heights (rows, cols) the reconstruction whose
        true error is fed back; default Delaunay-linear (nearest sample outside the hull).

    Returns
    -------
    ndarray of int64, shape (k,)
        Sorted distinct flat indices.

    Notes
    -----
    Cells where the smoothed error is (numerically) zero rank by their distance to the nearest
    sample, so flat regions fill their largest holes first.
    """
    del rng
    truth = _check_truth(truth, k)
    o = options or OracleGreedyOptions()
    shape, n = truth.shape, truth.size
    if reconstruct is None:

        def reconstruct(rc, values):
            return _linear(rc, values, shape)

    flat = framed_grid(shape, max(4, int(o.start_share * k)))
    sampled = np.zeros(n, dtype=bool)
    sampled[flat] = True
    while flat.size < k:
        rec = np.asarray(
            reconstruct(np.column_stack(np.divmod(flat, shape[1])), truth.ravel()[flat]),
            dtype=np.float64,
        )
        if rec.shape != shape:
            raise ValueError(f"reconstruct returned shape {rec.shape}, the truth's is {shape}")
        pitch = np.sqrt(n / flat.size)
        e2 = ndimage.gaussian_filter(
            (rec - truth) ** 2, sigma=o.smooth_pitch * pitch, mode="nearest"
        )
        hole = ndimage.distance_transform_edt(~sampled.reshape(shape))
        top = float(e2.max())
        # the hole term only orders cells whose error is negligible against the largest
        score = e2 + (1e-9 * top if top > 0 else 1.0) * hole / max(float(hole.max()), 1.0)
        m = min(int(np.ceil(o.batch_share * flat.size)), k - flat.size)
        new = _batch(score, sampled, m, max(3, 2 * int(o.nms_pitch * pitch / 2) + 1))
        sampled[new] = True
        flat = np.concatenate((flat, new))
    return np.sort(flat)


def hessian_norm(truth, *, sigma: float = 1.0) -> np.ndarray:
    """Frobenius norm of the depth's Hessian (finite differences), Gaussian-smoothed.

    Parameters
    ----------
    truth : array_like, shape (rows, cols)
        Depth map.
    sigma : float, >= 0
        Gaussian sigma (pixels) of the smoothing of the norm (0: none).

    Returns
    -------
    ndarray of float64, shape (rows, cols)
        |H| >= 0 (depth units per pixel^2).
    """
    z = np.asarray(truth, dtype=np.float64)
    gr, gc = np.gradient(z)
    hrr, hrc = np.gradient(gr)
    hcr, hcc = np.gradient(gc)
    h = np.sqrt(hrr**2 + hrc**2 + hcr**2 + hcc**2)
    return ndimage.gaussian_filter(h, sigma) if sigma > 0 else h


def oracle_hessian(
    truth, k: int, *, rng=None, options: OracleHessianOptions | None = None
) -> np.ndarray:
    """Density |H|^p of the true depth, placed by halftone + weighted Lloyd (an oracle bound).

    Parameters
    ----------
    truth : array_like, shape (rows, cols)
        True depth (finite).
    k : int
        Number of samples, 4 <= k <= rows * cols.
    rng : None, int, SeedSequence or Generator
        Randomness of the halftone.
    options : OracleHessianOptions, optional
        The density mapping and the Lloyd placement.

    Returns
    -------
    ndarray of int64, shape (k,)
        Sorted distinct flat indices.
    """
    truth = _check_truth(truth, k)
    o = options or OracleHessianOptions()
    density = density_from_map(hessian_norm(truth), power=o.density_power, mix=o.uniform_mix)
    return place(density, k, rng=rng, iterations=o.lloyd_iterations, border=o.border_pitch)
