"""Calibrate the image's shading from the samples and the image alone (paper eq. 3.5).

On dry, barren, rocky terrain under one sun the image is nearly linear in the slope along the
light (the paper, eq. 3.5: ``I ~ a + b (s . grad z)``; for a Lambert surface
``I = rho (s_up - s_h . grad h) / |n|``). Neither ``a`` nor ``b`` (nor the light's azimuth) is
needed in advance: the samples' linear reconstruction ``z_lin`` carries the low-frequency
slopes, and the image is regressed on them at the scale the samples resolve.

Method (measured by the project; ``docs/reconstruction.md``, "Calibration from the samples alone"):
blur the image and ``z_lin`` with one Gaussian (sigma = ``sigma_pitch`` x pitch, pitch =
density^-1/2 cells) and fit ``I_blur ~ a + b_r d_r z_blur + b_c d_c z_blur`` by least squares
over valid pixels (neither shadowed nor saturated) *inside the samples' convex hull*, away from
its edge by the blur's reach, and within about a pitch of a sample (long thin triangles along
the grid's edges or wide gaps have poor slopes that dilute ``b``). The pitfall it avoids:
unblurred gradients and nearest-filled cells outside the hull gave ``b`` 10-30x too small on
sparse grid and random layouts.

``b`` is signed: its direction ``b / |b|`` is the image direction along which the values' slope
brightens the image. For heights that is away from the sun (``-s_h``), for depths (whose
slope has the opposite sign) towards it. The fit's R^2 is the share of the (blurred) image
variance that shading explains; a held-out R^2 (fitted on one checkerboard half of blocks of
``block_pitches`` pitches, scored on the other, both ways) guards against overfitting noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from simlunar.reconstruction._anchor import LinearField, linear_field
from simlunar.reconstruction.integrate import gaussian_smooth
from simlunar.registry import Options, option

__all__ = [
    "Calibration",
    "CalibrationOptions",
    "calibrate",
    "lit_level",
    "lit_mask",
    "valid_pixels",
]


@dataclass(frozen=True)
class CalibrationOptions(Options):
    """Options of :func:`calibrate`."""

    sigma_pitch: float = option(
        0.5, doc="Gaussian sigma of the blur as a fraction of the sample pitch", gt=0, le=4
    )
    shadow: float = option(
        0.02,
        doc="pixels at or below this fraction of the image's 99th percentile are shadowed",
        ge=0,
        lt=1,
    )
    saturation: float = option(
        1.0,
        doc="image level at or above which a pixel is saturated (sensor images in [0, 1])",
        gt=0,
    )
    interior: float = option(
        0.95,
        doc="least blurred weight of valid in-hull pixels around a pixel for it to enter the fit",
        gt=0,
        le=1,
    )
    reach: float = option(
        1.0,
        doc="cells farther than this many sample pitches from every sample stay out of the fit "
        "(the linear reconstruction's slopes are poor in wide gaps and long edge triangles)",
        gt=0,
    )
    block_pitches: float = option(
        4.0, doc="side of the held-out checkerboard blocks in sample pitches", gt=0
    )


@dataclass(frozen=True, eq=False)
class Calibration:
    """The shading model ``I ~ a + b . grad z`` fitted on the samples.

    Attributes
    ----------
    a : float
        Image level of a flat patch (image units).
    b : ndarray, shape (2,)
        (b_row, b_col): image change per unit slope of the values (image units per dz/dx).
    direction : ndarray, shape (2,)
        ``b / |b|`` (zeros when ``b`` is 0): the image brightens as the values rise along it;
        for heights it points away from the sun's azimuth, for depths towards it.
    azimuth_deg : float
        ``atan2(b_col, b_row)`` in degrees (NaN when ``b`` is 0).
    share : float
        R^2 of the fit: the share of the blurred image variance explained by shading (0 when
        the image or the slopes do not vary).
    heldout_share : float
        R^2 on held-out blocks (NaN when too few pixels), may be negative.
    n_pixels : int
        Cells in the fit (blocks of the coarse grid it is made on, times their cells).
    sigma : float
        The blur (cells).
    """

    a: float
    b: np.ndarray
    direction: np.ndarray
    azimuth_deg: float
    share: float
    heldout_share: float
    n_pixels: int
    sigma: float

    @property
    def gain(self) -> float:
        """``|b|``."""
        return float(np.hypot(*self.b))

    @property
    def usable_share(self) -> float:
        """The held-out share (never above the in-sample one); 0 when there is none.

        A fit whose held-out share cannot be formed (under 10 blurred cells per checkerboard
        colour: a sparse layout on a view mostly in shadow) rests on a few dozen cells, and
        its in-sample share is no evidence: under a 2 deg sun at 1/2048 one such fit was 14 deg
        off the sun's azimuth with a third of the gain, and the image's detail took the result
        to 0.81x of linear. Such a fit is not used.
        """
        h = self.heldout_share
        return float(min(h, self.share)) if np.isfinite(h) else 0.0


#: a pixel whose neighbourhood is under this share of the frame's bright level is unlit
UNLIT_SHARE = 0.02
#: the neighbourhood (cells, square, odd) over which :func:`lit_mask` averages before judging
LIT_WINDOW = 15


def lit_mask(image) -> np.ndarray:
    """The frame's lit pixels (bool, its shape): those whose ``LIT_WINDOW``-square mean is above
    ``UNLIT_SHARE`` of the 99th percentile of those means (taken over every 7th value on large
    frames), shrunk by a window so the dark side of a beam's edge (which the window's mean still
    reaches) is left out; none when that percentile is not positive.

    Judged on the window's mean, not per pixel: a lit frame dominated by noise (flash-on minus
    flash-off with a flash of 0.01 x the sun: ~190 % per pixel, a third of its pixels below 2 %
    of its 99th percentile) is lit everywhere, as it is; only a region the light does not reach
    (a beam narrower than the view) is dark at the window's scale.
    """
    f = np.asarray(image, dtype=np.float64)
    w = min(LIT_WINDOW, *f.shape) if f.size else 1
    w -= 1 - w % 2  # odd: centred on the pixel
    box = ndimage.uniform_filter(f, size=w, mode="nearest")
    flat = box.ravel()
    ref = float(np.percentile(flat if flat.size < 100_000 else flat[::7], 99.0))
    if not ref > 0:
        return np.zeros(f.shape, dtype=bool)
    lit = box > UNLIT_SHARE * ref
    if lit.all():
        return lit
    inner = ndimage.minimum_filter(lit, size=2 * w + 1, mode="nearest")
    return inner if inner.any() else lit


def lit_level(image, lit: np.ndarray | None = None) -> float:
    """A frame's typical lit value: the median of its lit pixels (:func:`lit_mask`, or ``lit``
    when given; 0 when none is). The plain median where every pixel is lit (then the two are
    the same number); where a light reaches part of the view only (a flash's beam narrower
    than the field, most of it black), the median of the whole frame is 0 and every rule
    relative to it (the flat's guard, the noise estimate) would take the black for the level.
    """
    f = np.asarray(image, dtype=np.float64)
    lit = lit_mask(f) if lit is None else lit
    if lit.all():
        return float(np.median(f))
    return float(np.median(f[lit])) if lit.any() else 0.0


def valid_pixels(image, options: CalibrationOptions | None = None) -> np.ndarray:
    """Pixels neither shadowed nor saturated (bool, shape of ``image``).

    Shadowed: at or below ``shadow`` x the 99th percentile of the image (taken over every
    7th pixel on large images); saturated: at or above ``saturation``.
    """
    o = options or CalibrationOptions()
    img = np.asarray(image, dtype=np.float64)
    flat = img.ravel()
    ref = float(np.percentile(flat if flat.size < 100_000 else flat[::7], 99.0))
    valid = img < o.saturation
    if ref > 0:
        valid &= img > o.shadow * ref
    return valid


def _design(gr, gc, y):
    return np.column_stack((np.ones_like(y), gr, gc)), y


def _solve(xtx, xty, scale):
    """Least-squares (a, b_r, b_c) from the normal equations; slopes whose spread is under
    1e-12 of their mean square (a plane) are not fitted (b = 0)."""
    n = xtx[0, 0]
    mean = xtx[0] / n
    cov = xtx[1:, 1:] / n - np.outer(mean[1:], mean[1:])
    cxy = xty[1:] / n - mean[1:] * (xty[0] / n)
    tr = float(np.trace(cov))
    if not np.isfinite(tr) or tr <= 1e-12 * max(scale, 1e-300):
        b = np.zeros(2)
    else:
        b = np.linalg.lstsq(cov, cxy, rcond=1e-9)[0]
    a = xty[0] / n - mean[1:] @ b
    return np.array([a, *b])


def _stats(x, y):
    return x.T @ x, x.T @ y, float(y @ y), float(y.sum()), len(y)


def _r2(theta, stats, level):
    """R^2 of ``theta`` on ``stats`` of a centred ``y``; 0 when ``y`` varies by less than
    1e-10 of its ``level`` (a constant image, to rounding)."""
    xtx, xty, yty, ysum, n = stats
    ss_tot = yty - ysum * ysum / n
    if ss_tot <= n * (1e-10 * level) ** 2 or ss_tot <= 0:
        return 0.0
    ss_res = yty - 2.0 * theta @ xty + theta @ xtx @ theta
    return float(1.0 - max(ss_res, 0.0) / ss_tot)


def _blurred_fields(
    img, lin: LinearField, ok, *, spacing: float, sigma: float, o: CalibrationOptions
):
    """The image and the heights' slopes (1/m) blurred on a grid coarser by ``f``, and the
    coarse cells fit to use (valid, inside the hull, near samples).

    Block means, then the Gaussian of ``sigma / f`` coarse cells: together a kernel of variance
    ``sigma^2 + f^2 / 12``, ``f <= sigma / 2``. The heights are blurred before their slopes are
    taken (mirrored at the grid's edges, which damps the slopes of the long edge triangles
    there).

    Returns
    -------
    f, image, slope_rows, slope_cols, inner
    """
    f = max(1, int(sigma // 2))
    ib = gaussian_smooth(_blocks(img, f), sigma / f)
    zb = gaussian_smooth(_blocks(lin.heights, f), sigma / f)
    gr_b, gc_b = np.gradient(zb)
    gr_b /= f * spacing
    gc_b /= f * spacing
    mask = _blocks((ok & lin.hull).astype(np.float64), f)
    inner = (gaussian_smooth(mask, sigma / f) >= o.interior) & (mask == 1.0)
    inner &= _near_samples(lin.points, inner.shape, f) <= o.reach * lin.pitch
    return f, ib, gr_b, gc_b, inner


def _heldout_share(halves, scale: float, level: float) -> float:
    """Mean explained share of each checkerboard colour by the fit on the other (NaN when a
    colour has fewer than 10 cells)."""
    held = []
    if min(halves[0][4], halves[1][4]) >= 10:
        for fit, out in (halves, halves[::-1]):
            held.append(_r2(_solve(fit[0], fit[1], scale), out, abs(level)))
    return float(np.mean(held)) if held else math.nan


def calibrate(
    image,
    points_rc,
    values,
    *,
    spacing: float = 1.0,
    valid=None,
    linear: LinearField | None = None,
    options: CalibrationOptions | None = None,
) -> Calibration:
    """Fit ``I ~ a + b . grad z`` from the samples and the image.

    Parameters
    ----------
    image : array_like, shape (rows, cols)
        The frame (or an albedo-cancelling ratio of frames), linear intensity.
    points_rc : array_like, shape (k, 2)
        Measured cells (row, col).
    values : array_like, shape (k,)
        Measured heights or depths (m).
    spacing : float
        Cell size (m): slopes are dz / (cells x spacing).
    valid : array_like of bool, shape (rows, cols), optional
        Pixels usable for the fit; default :func:`valid_pixels` of ``image``.
    linear : LinearField, optional
        The samples' linear reconstruction if already computed.
    options : CalibrationOptions, optional

    Returns
    -------
    Calibration
    """
    o = options or CalibrationOptions()
    img = np.asarray(image, dtype=np.float64)
    if img.ndim != 2 or not np.isfinite(img).all():
        raise ValueError(f"image must be a finite (rows, cols) array, got shape {img.shape}")
    lin = linear if linear is not None else linear_field(points_rc, values, img.shape)
    if lin.shape != img.shape:
        raise ValueError(f"the samples' grid {lin.shape} is not the image's {img.shape}")
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing must be a finite number > 0, got {spacing!r}")
    ok = valid_pixels(img, o) if valid is None else np.asarray(valid, dtype=bool)
    if ok.shape != img.shape:
        raise ValueError(f"valid has shape {ok.shape}, the image {img.shape}")
    sigma = o.sigma_pitch * lin.pitch
    empty = Calibration(0.0, np.zeros(2), np.zeros(2), math.nan, 0.0, math.nan, 0, sigma)
    f, ib, gr_b, gc_b, inner = _blurred_fields(img, lin, ok, spacing=spacing, sigma=sigma, o=o)
    if inner.sum() < 10:
        return empty
    idx = np.flatnonzero(inner)
    y = ib.ravel()[idx]
    gr = gr_b.ravel()[idx]
    gc = gc_b.ravel()[idx]
    level = float(np.mean(y))
    x, y = _design(gr, gc, y - level)  # centred: the sums below keep their precision
    scale = float(np.mean(gr * gr + gc * gc))
    # held out: checkerboard blocks, fitted on one colour and scored on the other, both ways
    block = max(o.block_pitches * lin.pitch / f, 1.0)
    cols = inner.shape[1]
    colour = ((idx // cols) // block + (idx % cols) // block).astype(np.int64) % 2 == 0
    halves = [_stats(x[colour], y[colour]), _stats(x[~colour], y[~colour])]
    full = tuple(p + q for p, q in zip(*halves, strict=True))
    theta = _solve(full[0], full[1], scale)
    share = max(_r2(theta, full, abs(level)), 0.0)
    theta[0] += level
    heldout = _heldout_share(halves, scale, level)
    b = theta[1:].copy()
    gain = float(np.hypot(*b))
    if share == 0.0 or gain == 0.0:
        b[:] = 0.0
        gain = 0.0
    direction = b / gain if gain > 0 else np.zeros(2)
    az = math.degrees(math.atan2(b[1], b[0])) if gain > 0 else math.nan
    for arr in (b, direction):
        arr.setflags(write=False)
    n = len(y) * f * f
    return Calibration(float(theta[0]), b, direction, az, share, heldout, n, sigma)


def _near_samples(points: np.ndarray, shape, f: int) -> np.ndarray:
    """Distance (cells) from each block of the coarse grid to the nearest block holding a
    sample."""
    r = np.clip(np.floor(points[:, 0] / f).astype(np.int64), 0, shape[0] - 1)
    c = np.clip(np.floor(points[:, 1] / f).astype(np.int64), 0, shape[1] - 1)
    empty = np.ones(shape, dtype=bool)
    empty[r, c] = False
    return ndimage.distance_transform_edt(empty) * f


def _blocks(a: np.ndarray, f: int) -> np.ndarray:
    """Means over f x f blocks (the rows and columns beyond a multiple of f left out)."""
    if f == 1:
        return a
    r, c = (a.shape[0] // f) * f, (a.shape[1] // f) * f
    if r == 0 or c == 0:
        return a[:0, :0]
    return a[:r, :c].reshape(r // f, f, c // f, f).mean(axis=(1, 3))
