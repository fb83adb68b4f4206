"""Image -> importance maps of the paper's sampling study: gradient, entropy, wavelet energy.

Each map is float64 (rows, cols), >= 0, computed on the gray image (``to_gray``) of the guide.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pywt

from simlunar.features._kernels import sliding_entropy
from simlunar.registry import Options, option

__all__ = [
    "BOUNDARIES",
    "MAX_ENTROPY_SIZE",
    "RGB2GRAY",
    "EntropyOptions",
    "WaveletOptions",
    "check_entropy_size",
    "check_image",
    "entropy",
    "gradient",
    "to_gray",
    "to_uint8",
    "wavelet",
    "wavelet_levels",
]

# MATLAB rgb2gray weights (Rec. 601 luma as rounded by MATLAB's documentation), so that the
# paper's MATLAB features see the same gray image.
RGB2GRAY = np.array([0.298936021293775, 0.587043074451121, 0.114020904255103])


def check_image(image, *, name: str = "image") -> np.ndarray:
    """Validate a gray (rows, cols) or colour (rows, cols, 3) image and return it as float64."""
    img = np.asarray(image, dtype=np.float64)
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[..., 0]
    if not (img.ndim == 2 or (img.ndim == 3 and img.shape[2] == 3)):
        raise ValueError(f"{name} must have shape (rows, cols) or (rows, cols, 3), got {img.shape}")
    if img.shape[0] < 2 or img.shape[1] < 2:
        raise ValueError(f"{name} must be at least 2 x 2 pixels, got {img.shape[:2]}")
    if not np.all(np.isfinite(img)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return img


def to_gray(image) -> np.ndarray:
    """Gray float64 (rows, cols) image: identity for gray, MATLAB ``rgb2gray`` weights for RGB."""
    img = check_image(image)
    return img @ RGB2GRAY if img.ndim == 3 else img


def to_uint8(gray, *, scale: str = "minmax") -> np.ndarray:
    """Quantise a gray image to 8 bits (256 levels).

    Parameters
    ----------
    gray : ndarray, shape (rows, cols)
    scale : {"minmax", "unit"}
        ``"minmax"`` maps [min, max] to [0, 255] (radiance images have no fixed range);
        ``"unit"`` is MATLAB ``im2uint8`` for double images: clip to [0, 1], times 255, round
        half away from zero as MATLAB's ``uint8()`` does (76.5 -> 77; ``numpy.rint`` would
        give 76), no rescaling.
    """
    g = np.asarray(gray, dtype=np.float64)
    if scale == "minmax":
        lo, hi = float(g.min()), float(g.max())
        g = (g - lo) / (hi - lo) if hi > lo else np.zeros_like(g)
    elif scale != "unit":
        raise ValueError(f"unknown scale {scale!r}; valid: minmax, unit")
    return np.floor(np.clip(g, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def gradient(image) -> np.ndarray:
    """Gradient magnitude sqrt(Ix^2 + Iy^2) with MATLAB ``gradient`` semantics.

    Central differences inside, one-sided differences at the borders, unit spacing: the same as
    ``numpy.gradient`` with its default ``edge_order=1``.
    """
    g = to_gray(image)
    gy, gx = np.gradient(g)
    return np.hypot(gx, gy)


_NLOG_N = np.array([0.0] + [n * np.log2(n) for n in range(1, 4097)])


#: largest entropy window side (the sliding histogram counts at most 4096 pixels)
MAX_ENTROPY_SIZE = 63


def check_entropy_size(size: int) -> None:
    """Raise ValueError unless ``size`` is an odd entropy window side in 1..63."""
    if (
        isinstance(size, bool)
        or int(size) != size
        or size < 1
        or size % 2 == 0
        or size > MAX_ENTROPY_SIZE
    ):
        raise ValueError(f"entropy window size must be odd, 1..{MAX_ENTROPY_SIZE}, got {size}")


@dataclass(frozen=True)
class EntropyOptions(Options):
    """Options of the entropy map (:func:`entropy`)."""

    size: int = option(9, doc="entropy map: odd window side, 1..63", unit="px", ge=1)
    scale: str = option("minmax", doc="entropy map: 8-bit scaling", choices=("minmax", "unit"))

    def __post_init__(self):
        super().__post_init__()
        check_entropy_size(self.size)  # odd, at most MAX_ENTROPY_SIZE


def entropy(image, *, size: int = 9, scale: str = "minmax") -> np.ndarray:
    """Local Shannon entropy (bits) in a ``size`` x ``size`` window, MATLAB ``entropyfilt``.

    As ``entropyfilt``: 256 bins on the 8-bit image, symmetric padding (``padarray(...,
    'symmetric')`` = ``numpy.pad(mode="symmetric")``), a full ``size`` x ``size``
    neighbourhood (``true(9)``), log base 2. The 8-bit image comes from :func:`to_uint8`
    (``scale``). A sliding-histogram kernel makes it O(size) per pixel.

    **MATLAB parity** (the paper's tables used MATLAB): ``scale="unit"`` with the default
    ``size=9`` is ``entropyfilt(I)`` for a double image ``I`` in [0, 1]: ``im2uint8`` without
    min-max rescaling (values outside [0, 1] clip, MATLAB rounding). The default
    ``scale="minmax"`` stretches the image to the full 8-bit range first, which gives more
    occupied bins and higher entropies on dim images (1.5 bits more on average on a
    camera-lit scene). The table experiments use ``scale: unit``.

    Parameters
    ----------
    image : ndarray, shape (rows, cols) or (rows, cols, 3)
    size : int
        Odd window side in pixels (default 9, the MATLAB default).
    scale : {"minmax", "unit"}
        8-bit quantisation, see :func:`to_uint8`; ``"unit"`` for MATLAB parity.
    """
    check_entropy_size(size)
    u8 = to_uint8(to_gray(image), scale=scale)
    half = size // 2
    padded = np.pad(u8, half, mode="symmetric")
    return np.maximum(sliding_entropy(padded, size, _NLOG_N), 0.0)


BOUNDARIES = ("symmetric", "periodic")


@dataclass(frozen=True)
class WaveletOptions(Options):
    """Options of the wavelet energy map (:func:`wavelet`)."""

    wavelet: str = option("db2", doc="wavelet map: PyWavelets wavelet name")
    levels: int | None = option(
        None, doc="wavelet map: decomposition levels summed, finest first; null = all", ge=1
    )
    boundary: str = option("symmetric", doc="wavelet map", choices=BOUNDARIES)

    def __post_init__(self):
        super().__post_init__()
        if isinstance(self.levels, float):
            raise ValueError(f"levels must be an integer, got {self.levels!r}")
        if self.wavelet not in pywt.wavelist(kind="discrete"):
            raise ValueError(f"unknown discrete wavelet {self.wavelet!r} (e.g. db2, haar, sym4)")


def _wavelet_level_energy(image, wavelet, levels, boundary):
    """Per-pixel detail energy of each level on the coefficient grid, coarsest first."""
    g = to_gray(image)
    out_shape = g.shape
    if boundary == "symmetric":
        # Periodising the mirrored image is symmetric (half-point) extension at every border
        # (MATLAB wavedec's default 'sym' mode) while keeping the dyadic subregions aligned;
        # plain periodisation would wrap the left edge onto the right as a false step.
        g = np.pad(g, ((0, g.shape[0]), (0, g.shape[1])), mode="symmetric")
    elif boundary != "periodic":
        raise ValueError(f"unknown wavelet boundary {boundary!r}; valid: {', '.join(BOUNDARIES)}")
    rows, cols = g.shape
    w = pywt.Wavelet(wavelet)
    if levels is None:
        levels = max(pywt.dwt_max_level(min(rows, cols), w.dec_len), 1)
    if levels < 1:
        raise ValueError(f"wavelet levels must be >= 1, got {levels}")
    coeffs = pywt.wavedec2(g, w, mode="periodization", level=levels)
    out = []
    # coeffs[1] is the coarsest detail level (j = levels), coeffs[-1] the finest (j = 1)
    for j, details in zip(range(levels, 0, -1), coeffs[1:]):
        energy = details[0] ** 2 + details[1] ** 2 + details[2] ** 2
        block = 2**j
        nr, nc = energy.shape
        # pixels per subregion, fewer in the last row/column of blocks when n % 2^j != 0
        h = np.minimum(block, rows - block * np.arange(nr))
        wdt = np.minimum(block, cols - block * np.arange(nc))
        out.append((j, energy / np.outer(h, wdt), h, wdt))
    return out, out_shape


def wavelet_levels(
    image, *, wavelet: str = "db2", levels: int | None = None, boundary: str = "symmetric"
) -> list[np.ndarray]:
    """Per-level wavelet detail energy mapped back to the pixels, finest level first.

    The gray image is decomposed with ``pywt.wavedec2`` (periodization mode, so level j has
    ceil(n / 2^j) coefficients per axis and coefficient i covers pixels [i 2^j, (i+1) 2^j)).
    The detail energy cH^2 + cV^2 + cD^2 of each coefficient is spread evenly over the pixels of
    its subregion (divided by the subregion size), so each level's map sums to the energy of
    that level's detail coefficients (exactly so with ``boundary="periodic"``; with the default
    ``"symmetric"`` the decomposition is of the image mirrored to (2 rows, 2 cols) and the maps
    are that decomposition's maps cropped to the image).

    Returns
    -------
    list of ndarray, each float64 (rows, cols)
    """
    per_level, (rows, cols) = _wavelet_level_energy(image, wavelet, levels, boundary)
    maps = [np.repeat(np.repeat(e, h, axis=0), w, axis=1)[:rows, :cols] for _, e, h, w in per_level]
    return maps[::-1]


def wavelet(
    image, *, wavelet: str = "db2", levels: int | None = None, boundary: str = "symmetric"
) -> np.ndarray:
    """Wavelet energy map: the sum over levels of :func:`wavelet_levels` (paper section 4.1).

    Summed coarse to fine on the coefficient grids (each level's subregions split exactly into
    two of the next finer level's per axis), so only the last step is at full resolution.

    **Relation to MATLAB** ``wavedec2(I, n, 'db2')`` (default extension ``'sym'``): MATLAB
    extends the image half-point symmetrically *at every level* and keeps floor((n + 3) / 2)
    coefficients per axis for db2 (pywt ``mode="symmetric"`` is the same), so its level-j
    coefficients overhang the image by one or two and do not tile it in 2^j blocks. Here the
    image is mirrored once to (2 rows, 2 cols) and decomposed periodically: the extension at
    the image borders is the same half-point symmetric one at level 1, each level has exactly
    ceil(n / 2^j) coefficients that tile the image, and the deeper levels see the mirrored
    image instead of a re-extension of the previous approximation. The per-level detail
    energies therefore agree with MATLAB's in the interior and differ within a few
    coefficients (a filter length, 4 taps, per level) of the borders; the map is the energy
    per pixel of each coefficient's 2^j x 2^j subregion, summed over levels.

    Parameters
    ----------
    image : ndarray, shape (rows, cols) or (rows, cols, 3)
    wavelet : str
        PyWavelets name (default ``"db2"`` as in the paper).
    levels : int, optional
        Decomposition depth; default the maximum useful level ``pywt.dwt_max_level`` of the
        decomposed image.
    boundary : {"symmetric", "periodic"}
        Border handling, see :func:`wavelet_levels`.

    Returns
    -------
    ndarray of float64, shape (rows, cols), >= 0
    """
    per_level, (rows, cols) = _wavelet_level_energy(image, wavelet, levels, boundary)
    total = per_level[0][1]
    for _, energy, _, _ in per_level[1:]:
        nr, nc = energy.shape
        total = np.repeat(np.repeat(total, 2, axis=0)[:nr], 2, axis=1)[:, :nc] + energy
    return np.repeat(np.repeat(total, 2, axis=0)[:rows], 2, axis=1)[:, :cols]
