"""Image-anchored reconstruction: the slope along the light read from the image, integrated and
re-anchored to the samples (registry name ``"shading"``).

Physics (the paper, eq. 3.5): on dry, barren, rocky terrain under one sun the image is nearly
linear in the slope along the light, ``I ~ a + b . grad z``. :mod:`.calibration` fits ``a`` and
``b`` from the samples and the image alone. Then, with ``u = b / |b|`` and ``t`` across it:

1. the slope along ``u`` from the (lightly smoothed) image:
   ``p_s = clip((I_smooth - a) / (g |b|), -clip, clip)``; shadowed or saturated pixels take the
   linear reconstruction's slope;
2. the slope across ``u`` from the linear reconstruction ``z_lin``;
3. the slope field ``p_s u + p_t t`` integrated by Frankot-Chellappa on the mirror-extended
   grid (:func:`.integrate.frankot_chellappa`), the slope across ``u`` weighted by
   ``across_weight`` (the isotropic projection, weight 1, keeps only ``cos^2`` of each mode's
   detail along ``u``, since ``p_t`` is smoother than the truth): ``z_fc``;
4. re-anchored: ``z_a = z_fc + linear_interp(samples of (z - z_fc))``, which equals every
   sample and keeps ``z_fc``'s detail between them;
5. ``z = z_lin + gamma * hull * (z_a - z_lin)`` (outside the samples' convex hull the linear
   reconstruction's nearest-sample fill is kept).

**Albedo.** When the guide holds a co-located (camera-centred light) frame ``flat``, the ratio
``I / flat`` replaces ``I``: at opposition a Lambert (or Lommel-Seeliger) frame is albedo times
a nearly constant factor, so the ratio cancels albedo and keeps shading (for Lambert seen from
the nadir the ratio is exactly ``s_up - s_h . grad h``). When the guide holds frames under other
suns, each is calibrated the same way and the slope is solved per pixel from all of them
(photometric stereo: two light azimuths give both slope components from the image), each
weighted by its explained-variance share ``w = share / (1 - share)``.

**When the image does not help** (the fallback rule): ``gamma = gamma_max * clip((share -
share_lo) / (share_hi - share_lo), 0, 1)`` where ``share`` is the calibration's held-out
explained-variance share (the in-sample one when too few pixels, never more than it). Under a
high sun or camera-centred light the image is mostly albedo, the share falls and the result
falls back to the linear reconstruction: never clearly worse than linear, and equal to it when
the image does not vary. The share is measured at the calibration's blur (half a pitch), not
at the sub-pitch scales the method adds, so a second check caps ``gamma`` (``heldout_check``, on by
default, :func:`.heldout.heldout_gamma`): every fifth sample is left out and the least-squares
weight of the image's detail that predicts the left-out samples from the others is the largest
``gamma`` allowed; when one split leaves fewer than 20 held-out samples in the hull (the sparse
end) the five splits are pooled, and each split's detail is made again from its kept samples
only (the calibration, the slopes the image does not give and the flat-field all read the
samples).
On the full-resolution moonyard under its 75 deg sun the share alone let the sun image
through at sparse densities (held-out share 0.5-0.65 at 1/1024-1/2048) where its detail is
albedo, 10x linear's MSE; the check finds that and keeps linear. The project measured
(``docs/reconstruction.md``, "When it fails" and "Measured numbers"; quarter-scale presets):
share 0.62 at a 30 deg sun (1.73-2.37x fewer samples than linear for equal MSE), 0.11 at 60 deg
(1.08x), 0.002 under camera-centred light (1.00x).

**A real flash** (``guide.flash``): its frame is flat-fielded from the rig's geometry on the
samples' linear surface (:mod:`.flatfield`). The flash lights off-centre cells obliquely, so
the flat-fielded frame keeps a first-order shading of the relief the samples miss, and the
ratio answers the slope along ``w = b + a k`` per pixel (:func:`.flatfield.flash_relief_gain`),
not along the sun's ``b`` (the first pass reads it along ``b``). ``flash_refine`` (off by default: twice the cost) makes a second
pass: the frame flat-fielded on the first pass's fused surface and its slopes read around
that surface's along ``w`` (least norm). Measured on the quarter-scale aerial_1 night flash
(``experiments/fusion_flash_quarter.yaml``, one terrain, 2 trials): samples saved 2.97x ->
3.76x, daylight at 1.0 x the sun 2.95x -> 3.68x; a second pass flat-fielded on the fused
surface but read along ``b`` alone 3.04x, read around the fused slopes along ``b`` 3.60x,
``w`` in both passes 3.50x. It does not close the gap to the ideal light: most of the gain is
the fused surface's slopes across the light, and the same second pass lifts the ideal frame
from 3.81x to 4.96x (night flash 0.76 of it; 0.78 with one pass each). A flat blurred by
``flat_noise`` wider than ``image_sigma`` keeps one pass (its shading at the scale the second
pass reads is gone; a rule set after seeing the daylight flashes of that experiment, blurred
1.1 and 11 pixels at 0.1 / 0.01 x the sun, refined 2.09x / 1.41x against 2.05x / 1.54x).

A co-located frame whose own noise (:func:`frame_noise`, estimated from the frame alone)
exceeds ``flat_noise`` -- a daylight
flash far weaker than the sun, flash-on minus flash-off -- is blurred down to that level first
(:func:`denoised_flat`): divided raw, its noise went into every pixel of the ratio with heavy
tails where it nears zero, and the held-out check, which sees the detail at ~1 % of the cells
(the samples), let it through: on a quarter-scale aerial_1 render with a flash of 0.1 x the sun
the top 1 % of cells held 90 % of the excess error and the result was 0.70x of linear at 1/16.

``info``: ``shading_share``, ``heldout_share``, ``gamma``, ``frames`` (e.g. ``"sun"``,
``"sun+camera"``, ``"sun+sun2"``), ``azimuth_deg`` (calibrated ``b``'s azimuth),
``gain`` (``|b|``), and ``light_axis_error_deg`` when the guide names the light.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from scipy import ndimage

from simlunar.reconstruction._anchor import LinearField, linear_field
from simlunar.reconstruction._reading import READING_OPTIONS, ReadingChecks
from simlunar.reconstruction.base import Guide, Reconstructed
from simlunar.reconstruction.calibration import (
    Calibration,
    CalibrationOptions,
    calibrate,
    lit_level,
    lit_mask,
    valid_pixels,
)
from simlunar.reconstruction.flatfield import flash_relief_gain, flat_field
from simlunar.reconstruction.heldout import blend_detail, checked_blend
from simlunar.reconstruction.integrate import central_gradient, frankot_chellappa
from simlunar.reconstruction.shadow import ShadowOptions, shadow_mask
from simlunar.registry import option, shared_option

__all__ = [
    "ShadingOptions",
    "denoised_flat",
    "fallback_gamma",
    "frame_noise",
    "fuse_slopes",
    "shading",
    "shading_frames",
    "shadow_masks",
]


@dataclass(frozen=True)
class ShadingOptions(ReadingChecks):
    """Options of the image-anchored reconstruction (:func:`shading`)."""

    gain: float = shared_option(READING_OPTIONS, "gain")
    clip: float = shared_option(READING_OPTIONS, "clip")
    image_sigma: float = shared_option(READING_OPTIONS, "image_sigma")
    across_weight: float = option(
        0.1,
        doc="weight of the linear reconstruction's slope across the light in the integration "
        "(1: isotropic Frankot-Chellappa)",
        gt=0,
        le=1,
    )
    gamma_max: float = option(1.0, doc="weight of the image's detail at full share", ge=0, le=1)
    share_lo: float = shared_option(READING_OPTIONS, "share_lo")
    share_hi: float = shared_option(READING_OPTIONS, "share_hi")
    use_flat: bool = shared_option(READING_OPTIONS, "use_flat")
    use_others: bool = option(
        True, doc="photometric stereo with the guide's other-sun frames", choices=(True, False)
    )
    flat_guard: float = option(
        0.05,
        doc="flat pixels under this fraction of the flat's median are left out (and guarded)",
        gt=0,
        lt=1,
    )
    stereo_condition: float = option(
        0.05,
        doc="least eigenvalue ratio of the frames' weighted directions for photometric stereo",
        gt=0,
        le=1,
    )
    sigma_pitch: float = shared_option(READING_OPTIONS, "sigma_pitch")
    shadow: float = shared_option(READING_OPTIONS, "shadow")
    saturation: float = shared_option(READING_OPTIONS, "saturation")
    shadow_lit: float = shared_option(READING_OPTIONS, "shadow_lit")
    detail_clip: float = shared_option(READING_OPTIONS, "detail_clip")
    heldout_check: bool = option(
        True,
        doc="cap gamma by a check on held-out samples: every fifth sample is left out, and the "
        "image's detail must predict its departure from the others' linear interpolation",
        choices=(True, False),
    )
    flat_noise: float = option(
        0.05,
        doc="relative noise of the co-located frame above which it is blurred down to it "
        "(estimated from the frame: denoised_flat)",
        gt=0,
        le=1,
    )
    flash_refine: bool = option(
        False,
        doc="a flash's flat frame (blurred by flat_noise no wider than image_sigma): a second "
        "pass flat-fielded on the first pass's fused surface, its slopes read around that "
        "surface's with the flash's relief gain per pixel (flatfield.flash_relief_gain); "
        "twice the cost",
        choices=(True, False),
    )

    def calibration(self) -> CalibrationOptions:
        return CalibrationOptions(
            sigma_pitch=self.sigma_pitch, shadow=self.shadow, saturation=self.saturation
        )


def fallback_gamma(share: float, options: ShadingOptions | None = None) -> float:
    """The stated fallback rule: ``gamma_max * clip((share - lo) / (hi - lo), 0, 1)``."""
    o = options or ShadingOptions()
    if not np.isfinite(share):
        return 0.0
    return float(o.gamma_max * np.clip((share - o.share_lo) / (o.share_hi - o.share_lo), 0, 1))


def shading_frames(
    guide: Guide,
    options: ShadingOptions | None = None,
    *,
    linear: LinearField | None = None,
    surface=None,
    flat=None,
    shadows=None,
):
    """The frames the slopes are read from: ``[(name, image, valid), ...]``.

    With a co-located frame (and ``use_flat``) every sun frame is divided by it (pixels where
    the flat is under ``flat_guard`` of its median are invalid and divided by that floor).
    When the co-located light is a flash on the rig (``guide.flash``), the flat is first
    flat-fielded with its geometry on the samples' linear surface ``linear``
    (:func:`.flatfield.flat_field`; required then), or on ``surface`` (rows, cols) when given
    (a fused surface of the same samples). ``flat``: the co-located frame already denoised
    (:func:`denoised_flat`; default: denoised here).
    Without one, the raw sun frames and, for each other sun, the ratio ``sun / sun_j``
    (albedo-free: ``(s1 . n) / (s2 . n)``, linear in the slope to first order, calibrated like
    any frame). Valid pixels are those neither saturated nor shadowed in the raw sun frames:
    shadowed by the global rule of :func:`.calibration.valid_pixels` or by
    :func:`shadow_masks` (the frames alone: each sun frame dark where it is under its local
    lit level, read on ``sun / flat`` where the co-located frame is lit); ``shadows``: those
    masks already made, one per sun frame (default: made here).
    """
    o = options or ShadingOptions()
    copt = o.calibration()
    suns = [("sun", guide.image)]
    if o.use_others:
        suns += [(f"sun{i + 2}", im) for i, (im, _) in enumerate(guide.others)]
    use_flat = guide.flat is not None and o.use_flat
    if use_flat and flat is None:
        flat = denoised_flat(guide.flat, o.flat_noise)
    if shadows is None:
        shadows = shadow_masks(guide, o, flat=flat if use_flat else None)
    if len(shadows) != len(suns):
        raise ValueError(f"shadows: {len(shadows)} masks for {len(suns)} sun frames")
    valid = [valid_pixels(im, copt) & ~sh for (_, im), sh in zip(suns, shadows, strict=True)]
    out = []
    if use_flat:
        if guide.flash is not None:
            if linear is None and surface is None:
                raise ValueError("a flash's flat frame is flat-fielded on the samples: give linear")
            if surface is None:
                flat = flat_field(
                    flat, linear.heights, guide.flash, spacing=guide.spacing, slopes=linear.slopes()
                )
            else:
                flat = flat_field(flat, surface, guide.flash, spacing=guide.spacing)
        # relative to the lit part: a flash's beam may light part of the view only
        med = lit_level(flat)
        floor = o.flat_guard * med if med > 0 else o.flat_guard
        lit = flat > floor
        den = np.maximum(flat, floor)
        for (name, im), v in zip(suns, valid, strict=True):
            out.append((name, im / den, v & lit))
    else:
        out = [(name, im, v) for (name, im), v in zip(suns, valid, strict=True)]
        # no co-located frame: the ratio of two sun frames cancels albedo too (one slope
        # component, along the difference of the two lights' s_h / s_up)
        for (name, im), v in zip(suns[1:], valid[1:], strict=True):
            med = float(np.median(im))
            floor = o.flat_guard * med if med > 0 else o.flat_guard
            ratio = suns[0][1] / np.maximum(im, floor)
            out.append((f"sun/{name}", ratio, valid[0] & v & (im > floor)))
    return out


def shadow_masks(guide: Guide, options: ShadingOptions | None = None, *, flat=None) -> list:
    """One shadow mask per sun frame the reconstruction reads (the guide's image, then its
    other suns when ``use_others``): :func:`.shadow.shadow_mask` of the frame, with the
    co-located frame ``flat`` (the guide's, denoised: :func:`denoised_flat`) when given; all
    False when ``shadow_lit`` is 0. The frames only: no sample, no truth."""
    o = options or ShadingOptions()
    suns = [guide.image]
    if o.use_others:
        suns += [im for im, _ in guide.others]
    sopt = ShadowOptions(lit_fraction=o.shadow_lit)
    return [shadow_mask(im, flat, options=sopt) for im in suns]


#: Immerkaer's (1996) noise mask: the difference of two Laplacians, blind to planes and ramps
_NOISE_MASK = np.array([[1.0, -2.0, 1.0], [-2.0, 4.0, -2.0], [1.0, -2.0, 1.0]])


def frame_noise(image) -> float:
    """Per-pixel noise of a frame relative to its median, estimated from the frame alone.

    Immerkaer's mask (J. Immerkaer, "Fast noise variance estimation", CVIU 64, 1996) responds
    to white noise of std ``s`` with std ``6 s`` and not to planes or linear ramps; the robust
    std of its response (1.4826 x MAD) over 6 estimates ``s``. Texture at the pixel scale
    (albedo) counts as noise here: on the project's quarter-scale aerial renders the ideal
    co-located frame and a night flash read 0.03, a daylight flash at 1 / 0.1 / 0.01 x the
    sun 0.04 / 0.20 / 1.9. Infinite when the median is not positive.
    """
    f = np.asarray(image, dtype=np.float64)
    lit = lit_mask(f)
    med = lit_level(f, lit)
    if f.shape[0] < 3 or f.shape[1] < 3 or not med > 0:
        return math.inf
    c = _noise_response(f, _NOISE_MASK)
    if not lit.all():
        # part of the view is unlit (a flash's beam): its black has no noise to measure;
        # the response where the 3 x 3 window is wholly lit
        inner = ndimage.binary_erosion(lit)[1:-1, 1:-1]
        if inner.any():
            c = c[inner]
    return float(1.4826 * np.median(np.abs(c - np.median(c))) / 6.0 / med)


@numba.njit(cache=True, nogil=True)
def _noise_response(f, mask):  # pragma: no cover - compiled
    """``ndimage.convolve(f, mask)[1:-1, 1:-1]`` of a symmetric 3 x 3 ``mask`` without zeros,
    to the bit: ndimage sums ``f * w`` over the kernel in row-major order from 0 (tests
    check it against ndimage)."""
    rows, cols = f.shape
    out = np.empty((rows - 2, cols - 2))
    for r in range(1, rows - 1):
        for c in range(1, cols - 1):
            t = 0.0
            for i in range(3):
                for j in range(3):
                    t += f[r - 1 + i, c - 1 + j] * mask[i, j]
            out[r - 1, c - 1] = t
    return out


def denoised_flat(flat, target: float) -> np.ndarray:
    """``flat`` blurred just enough that its relative noise (:func:`frame_noise`) falls to
    ``target``: a Gaussian of sigma ``nu / (2 sqrt(pi) target)`` pixels divides white noise by
    ``nu / target``; unchanged when its noise is at or under ``target`` already. A noisy flat
    (a daylight flash much weaker than the sun: flash-on minus flash-off) would otherwise put
    its noise into every pixel of the ratio, heavy-tailed where the flat nears zero."""
    return _denoised(flat, target)[0]


def _denoised(flat, target: float):
    """:func:`denoised_flat` and the sigma (pixels) of its blur (0: unchanged)."""
    nu = frame_noise(flat)
    if nu <= target:
        return flat, 0.0
    sigma = min(nu / (2.0 * math.sqrt(math.pi) * target), max(flat.shape) / 4.0)
    return ndimage.gaussian_filter(np.asarray(flat, np.float64), sigma, truncate=3.0), sigma


def _image_slope(image, valid, cal: Calibration, lin_along, o: ShadingOptions):
    """Slope along ``cal.direction`` read from one frame (linear's where invalid)."""
    smooth = ndimage.gaussian_filter(image, o.image_sigma, truncate=3.0) if o.image_sigma else image
    p = (smooth - cal.a) / (o.gain * cal.gain)
    np.clip(p, -o.clip, o.clip, out=p)
    return np.where(valid, p, lin_along)


def _flash_slopes(image, valid, cal: Calibration, guide: Guide, o, surface):
    """Slopes along and across ``cal.direction`` read from a flash ratio flat-fielded on a
    fused ``surface`` (a flash's second pass, ``flash_refine``).

    The flash lights each cell from its own direction, so the ratio flat-fielded on
    ``surface`` reads ``a + b . G_f + w . (G - G_f)`` with ``w = b + a k`` per pixel
    (:func:`.flatfield.flash_relief_gain`; ``G_f`` the fused surface's slope): one slope
    component, along ``w``, which turns away from ``b`` with the flash's tilt (up to ~0.5
    |b| at the corners of an aerial view from 50 m under a 30 deg sun). Its least-norm
    reading ``G - G_f = w (I - a - b . G_f) / |w|^2`` is added to the fused surface's
    slopes along and across ``u`` (unread pixels keep the fused surface's). ``k = 0`` (a
    light straight above) reads ``(I - a) / |b|`` along ``u``, as :func:`_image_slope` does.
    """
    u = cal.direction
    t = np.array([-u[1], u[0]])
    fr, fc = central_gradient(surface)
    fr /= guide.spacing
    fc /= guide.spacing
    k = flash_relief_gain(surface, guide.flash, spacing=guide.spacing)
    smooth = ndimage.gaussian_filter(image, o.image_sigma, truncate=3.0) if o.image_sigma else image
    b = cal.b
    rhs = smooth - cal.a - (b[0] * fr + b[1] * fc)
    wr = b[0] + cal.a * k[0]
    wc = b[1] + cal.a * k[1]
    # |w| >= ~0.46 |b| for a 30 deg sun and a light 43 deg off the vertical; the floor guards
    # a light along the sun (the ratio then carries no slope)
    rhs /= np.maximum(wr * wr + wc * wc, 1e-6 * float(b @ b))
    fused_along = u[0] * fr + u[1] * fc
    p_s = (fused_along + rhs * (wr * u[0] + wc * u[1])) / o.gain
    np.clip(p_s, -o.clip, o.clip, out=p_s)
    p_s = np.where(valid, p_s, fused_along)
    p_t = t[0] * fr + t[1] * fc + np.where(valid, rhs * (wr * t[0] + wc * t[1]) / o.gain, 0.0)
    return p_s, p_t


def fuse_slopes(
    lin: LinearField, gr, gc, gamma: float, *, spacing=1.0, along=None, across_weight=1.0
):
    """Integrate a slope field and re-anchor it on the samples (steps 3-5 of the method).

    Parameters
    ----------
    lin : LinearField
        The samples' linear reconstruction and hull.
    gr, gc : ndarray, shape (rows, cols)
        Slopes dz/dx along rows and columns (value units per metre).
    gamma : float
        Weight of the re-anchored detail.
    spacing : float
        Cell size (m).
    along, across_weight :
        The integration's trusted direction and the weight across it
        (:func:`.integrate.frankot_chellappa`).

    Returns
    -------
    ndarray, shape (rows, cols)
        ``z_lin + gamma * hull * (z_a - z_lin)``; equals the samples at their cells and, for
        a constant slope field over samples of that plane, the plane (to rounding).
    """
    z_fc = frankot_chellappa(gr * spacing, gc * spacing, along=along, across_weight=across_weight)
    return blend_detail(lin, z_fc, gamma)


def _axis_error(direction, light) -> float:
    """Angle (deg, 0-90) between the calibrated direction's axis and the light's azimuth."""
    h = np.asarray(light[:2], dtype=np.float64)
    if np.hypot(*h) < 1e-9 or not np.any(direction):
        return math.nan
    c = abs(float(direction @ h)) / float(np.hypot(*h))
    return math.degrees(math.acos(min(c, 1.0)))


def shading(points_rc, values, shape, *, guide: Guide, options: ShadingOptions | None = None):
    """Image-anchored reconstruction (see the module docstring).

    Parameters
    ----------
    points_rc : array_like, shape (k, 2)
        Measured cells (row, col).
    values : array_like, shape (k,)
        Measured heights or depths (m).
    shape : tuple of int
        Output grid (rows, cols), the guide's.
    guide : Guide
        The sun frame (and optionally the co-located frame and other-sun frames).
    options : ShadingOptions, optional

    Returns
    -------
    Reconstructed
        ``heights`` (rows, cols) float64 and ``info`` (see the module docstring).
    """
    o = options or ShadingOptions()
    if guide is None:
        raise ValueError("the shading reconstruction needs the guide image (guide=Guide(...))")
    lin = linear_field(points_rc, values, shape)
    if guide.shape != lin.shape:
        raise ValueError(f"guide image has shape {guide.shape}, the output grid {lin.shape}")
    # the co-located frame's denoising reads the frame alone: once for every pass and fold
    flat, blur = _denoised(guide.flat, o.flat_noise) if guide.flat is not None else (None, 0.0)
    # a flash's second pass reads the flat's shading at the image's own smoothing scale
    refine = o.flash_refine and o.use_flat and guide.flash is not None and blur <= o.image_sigma
    # the shadows are read from the frames alone: once for every pass and fold
    shadows = shadow_masks(guide, o, flat=flat if o.use_flat else None)
    z_fc, gamma, info = _refined_detail(lin, guide, o, flat, shadows, refine=refine)
    info["shadow_share"] = float(shadows[0].mean())
    if z_fc is None:
        return Reconstructed(lin.heights, info)

    # the detail is made from the samples (the calibration, the slopes where the image is not
    # read, the flat-field's surface): the check remakes it from the kept samples only
    def remade(keep):
        field = _refined_detail(keep, guide, o, flat, shadows, refine=refine)[0]
        return np.zeros(lin.shape) if field is None else field

    checked = remade if o.heldout_check else None
    z = checked_blend(lin, z_fc, gamma, info, remade=checked, pool_folds=True, clip=o.detail_clip)
    return Reconstructed(z, info)


def _refined_detail(
    lin: LinearField, guide: Guide, o: ShadingOptions, flat=None, shadows=None, *, refine=False
):
    """:func:`_shading_detail`, and for a flash's flat frame once more (``flash_refine``)
    flat-fielded on the fused surface of the first pass and read around its slopes with the
    flash's relief gain (:func:`_flash_slopes`): the flash lights off-centre cells obliquely
    (up to ~43 deg from the vertical at the corners of an aerial view from 50 m), so its frame
    keeps a first-order shading of the relief the samples do not resolve, which the linear
    surface's normals cannot divide out, and turns the slope the ratio reads away from the
    sun's direction. ``refine``: whether to (:func:`shading` says so for ``flash_refine``
    unless :func:`denoised_flat` blurred the flat wider than ``image_sigma``: its shading at
    the scale this pass reads is gone)."""
    z_fc, gamma, info = _shading_detail(lin, guide, o, flat=flat, shadows=shadows)
    if z_fc is None or not refine:
        return z_fc, gamma, info
    fused = blend_detail(lin, z_fc, gamma)
    z2, gamma2, info2 = _shading_detail(lin, guide, o, surface=fused, flat=flat, shadows=shadows)
    if z2 is None:  # the refined frame reads nothing: keep the first pass
        return z_fc, gamma, info
    info2["flash_refined"] = 1.0
    return z2, gamma2, info2


def _shading_detail(
    lin: LinearField, guide: Guide, o: ShadingOptions, *, surface=None, flat=None, shadows=None
):
    """``(z_fc or None, gamma, info)``: the integrated slope field read from the guide on the
    samples of ``lin``, its weight by the fallback rule and the diagnostics (None when the
    image is not used); a flash's flat is flat-fielded on ``surface`` (default ``lin``'s)."""
    frames = shading_frames(guide, o, linear=lin, surface=surface, flat=flat, shadows=shadows)
    copt = o.calibration()
    cals = [
        calibrate(im, None, None, spacing=guide.spacing, valid=v, linear=lin, options=copt)
        for _, im, v in frames
    ]
    usable = [i for i, c in enumerate(cals) if c.gain > 0 and fallback_gamma(c.usable_share, o)]
    best = max(range(len(cals)), key=lambda i: cals[i].usable_share)
    cal0 = cals[best]
    # photometric stereo when two or more usable frames see different directions
    stereo = False
    if len(usable) >= 2:
        w = np.array([min(max(cals[i].usable_share, 0.0), 0.99) for i in usable])
        w = w / (1.0 - w)
        u = np.array([cals[i].direction for i in usable])
        a_mat = (w[:, None, None] * u[:, :, None] * u[:, None, :]).sum(axis=0)
        ev = np.linalg.eigvalsh(a_mat)
        stereo = ev[0] >= o.stereo_condition * ev[1]
    share = max(cals[i].usable_share for i in usable) if stereo else cal0.usable_share
    gamma = fallback_gamma(share, o)
    used = [frames[i][0] for i in usable] if stereo else [frames[best][0]]
    if guide.flat is not None and o.use_flat:
        used.extend(guide.flat_frames)
    info = {
        "shading_share": float(cal0.share),
        "heldout_share": float(cal0.heldout_share),
        "gamma": gamma,
        "frames": "+".join(used),
        "azimuth_deg": float(cal0.azimuth_deg),
        "gain": cal0.gain,
    }
    if guide.light is not None:
        info["light_axis_error_deg"] = _axis_error(cal0.direction, guide.light)
    if gamma == 0.0 or cal0.gain == 0.0:
        info["gamma"] = 0.0
        return None, 0.0, info
    lr, lc = (g / guide.spacing for g in lin.slopes())
    if stereo:
        rhs_r = np.zeros(lin.shape)
        rhs_c = np.zeros(lin.shape)
        for wi, i in zip(w, usable, strict=True):
            ui = cals[i].direction
            p = _image_slope(frames[i][1], frames[i][2], cals[i], ui[0] * lr + ui[1] * lc, o)
            p *= wi
            rhs_r += ui[0] * p
            rhs_c += ui[1] * p
        inv = np.linalg.inv(a_mat)
        gr = inv[0, 0] * rhs_r + inv[0, 1] * rhs_c
        gc = inv[1, 0] * rhs_r + inv[1, 1] * rhs_c
    else:
        u = cal0.direction
        t = np.array([-u[1], u[0]])
        _, im, v = frames[best]
        if surface is not None:  # a flash's second pass (flash_refine)
            p_s, p_t = _flash_slopes(im, v, cal0, guide, o, surface)
        else:
            p_s = _image_slope(im, v, cal0, u[0] * lr + u[1] * lc, o)
            p_t = t[0] * lr + t[1] * lc
        gr = p_s * u[0] + p_t * t[0]
        gc = p_s * u[1] + p_t * t[1]
    along, weight = (None, 1.0) if stereo else (cal0.direction, o.across_weight)
    sp = guide.spacing
    z_fc = frankot_chellappa(gr * sp, gc * sp, along=along, across_weight=weight)
    return z_fc, gamma, info
