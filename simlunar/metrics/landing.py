"""Landing-site scores: which hazards a reconstruction finds, per hazard size, and whether the
site it calls safe is safe.

Everything is measured on world points of a view (``(rows, cols, 3)``, z up, NaN where
unknown): the reconstruction's and the truth's, through the same functions, so a sensor is
judged only by what it measured. Lengths are given in metres and turned into pixels with the
view's ground sample distance (:func:`ground_sample_distance`, the median spacing of the true
points along a row).

Hazards (:class:`LandingOptions`):

- **rocks of height h** (one per ``rock_heights_m``, e.g. 0.15 m, the hazard size a lander
  scanning from a ~100 m hover looks for, and 0.30 m, the ALHAT requirement): pixels standing
  more than ``h`` above the median height of a ``footprint_m`` square around them
  (:func:`relief`); a rock is a connected group of such pixels (8-neighbours).
  ``hazard_recall_rock_<h>`` is the share of the *true* rocks that the reconstruction flags
  anywhere within one pixel of them; ``hazard_precision_rock_<h>`` the share of the
  reconstruction's flagged rocks that lie within one pixel of a true one (object counts: a
  boulder is one hazard however many pixels it covers).
- **slopes** steeper than ``slope_deg`` (5 deg: ALHAT) across the lander's footprint: the slope
  of the surface from central differences over ``footprint_m`` (:func:`slope_map`);
  ``hazard_recall_slope_<s>`` / ``hazard_precision_slope_<s>`` are pixel-wise (a slope is an
  area, not an object).

Both recall and precision are 1 when there is nothing to find / nothing was flagged, as in
:func:`simlunar.metrics.hazard.detection_scores`.

The landing question: candidate sites are discs of ``site_radius_m`` on a grid of
``site_pitch_m`` over the view; a site's hazard fraction is the share of its pixels flagged as a
rock of the largest size or a slope; the lander picks the site with the smallest
*reconstructed* fraction (ties: the one nearest the view's centre) and lands there if the
reconstruction calls it safe (fraction 0). ``false_safe_site`` is 1 when it lands on a site
that is *not* safe in the truth (0 when the site is safe or when it calls no site safe and
aborts); its mean over terrain seeds is the probability of landing on a hazard believing the
site safe. ``safe_site_called`` is 1 when the reconstruction offers a safe site at all, so
``mean(false_safe_site) / mean(safe_site_called)`` is the false-safe rate given a landing.

Surface errors: ``height_rms`` (m) the RMS of the reconstructed minus the true height, and
``slope_rms_deg`` the RMS of the reconstructed minus the true slope across the footprint, over
the pixels where both are known (the figures a DEM product quotes: NASA PGDA product 78 gives
0.30-0.50 m and 1.5-2.5 deg for LOLA-only 5 m DEMs, whose slope baseline is a few pixels).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from simlunar.metrics.hazard import _central
from simlunar.metrics.safe_site import SiteOptions, grid_sites, site_fractions
from simlunar.registry import Options, option

__all__ = [
    "LandingOptions",
    "ground_sample_distance",
    "landing_hazard_maps",
    "landing_metric_names",
    "landing_scores",
    "object_scores",
    "relief",
    "slope_map",
]


@dataclass(frozen=True)
class LandingOptions(Options):
    """Landing hazards by size and the landing site (module docstring for the definitions)."""

    rock_heights_m: tuple = option(
        (0.15, 0.30), doc="rock hazard sizes: heights above the footprint's median (m, each > 0)"
    )
    slope_deg: float = option(5.0, doc="largest safe slope across the footprint", unit="deg",
                              gt=0, lt=90)  # fmt: skip
    footprint_m: float = option(
        4.0, doc="lander footprint: slope baseline and the median window of a rock's height",
        unit="m", gt=0,
    )  # fmt: skip
    site_radius_m: float = option(4.0, doc="radius of a candidate landing site", unit="m", gt=0)
    site_pitch_m: float = option(8.0, doc="spacing of the candidate sites' centres", unit="m",
                                 gt=0)  # fmt: skip

    def __post_init__(self):
        super().__post_init__()
        h = np.asarray(self.rock_heights_m, float)
        if h.ndim != 1 or h.size == 0 or not np.all(np.isfinite(h)) or h.min() <= 0:
            raise ValueError(f"rock_heights_m must be heights > 0, got {self.rock_heights_m}")
        if len(set(_cm(v) for v in h)) != h.size:
            raise ValueError(f"rock_heights_m must differ by at least 1 cm: {self.rock_heights_m}")


def _cm(h: float) -> str:
    return f"{round(float(h) * 100):d}cm"


def _deg(s: float) -> str:
    return f"{float(s):g}deg"


def landing_metric_names(options: LandingOptions) -> list[str]:
    """The metric names :func:`landing_scores` returns, in its order."""
    names = []
    for h in options.rock_heights_m:
        names += [f"hazard_recall_rock_{_cm(h)}", f"hazard_precision_rock_{_cm(h)}"]
    s = _deg(options.slope_deg)
    names += [f"hazard_recall_slope_{s}", f"hazard_precision_slope_{s}"]
    return [*names, "false_safe_site", "safe_site_called", "height_rms", "slope_rms_deg"]


def ground_sample_distance(points: np.ndarray) -> float:
    """Median distance (m) in (x, y) between horizontally adjacent known points of a view."""
    p = np.asarray(points, float)
    d = np.hypot(*np.moveaxis(np.diff(p[..., :2], axis=1), -1, 0))
    d = d[np.isfinite(d) & (d > 0)]
    if d.size == 0:
        raise ValueError("ground_sample_distance: no two adjacent known points")
    return float(np.median(d))


def slope_map(points: np.ndarray, baseline_px: int) -> np.ndarray:
    """Slope (deg) of the surface from central differences of ``points`` over
    ``2 baseline_px`` pixels along each axis (the normal of the two difference vectors); NaN
    within ``baseline_px`` of the border and where a point is unknown."""
    p = np.asarray(points, float)
    s = int(baseline_px)
    if s < 1:
        raise ValueError(f"baseline_px must be >= 1, got {baseline_px}")
    diffs = [np.stack([_central(p[..., i], s, axis) for i in range(3)], -1) for axis in (1, 0)]
    n = np.cross(diffs[0], diffs[1])
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.abs(n[..., 2]) / np.linalg.norm(n, axis=-1)
    return np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))


def relief(points: np.ndarray, window_px: int) -> np.ndarray:
    """Height (m) of each point above the median height of the ``window_px`` square around it
    (unknown points take the view's median in the filter); NaN where unknown."""
    z = np.asarray(points, float)[..., 2]
    known = np.isfinite(z)
    if not known.any():
        return np.full(z.shape, np.nan)
    filled = np.where(known, z, np.median(z[known]))
    return np.where(known, z - ndimage.median_filter(filled, size=int(window_px)), np.nan)


_EIGHT = np.ones((3, 3), bool)


def object_scores(found: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """(recall, precision) of hazard objects: connected groups (8-neighbours) of flags.

    A true object is found when a flag of ``found`` lies on it or one pixel beside it; a found
    object is right when it lies on or one pixel beside a true one. 1 where there is nothing to
    find / nothing flagged.
    """
    found, truth = np.asarray(found, bool), np.asarray(truth, bool)
    t_lab, nt = ndimage.label(truth, structure=_EIGHT)
    f_lab, nf = ndimage.label(found, structure=_EIGHT)
    near_found = ndimage.binary_dilation(found, structure=_EIGHT)
    near_truth = ndimage.binary_dilation(truth, structure=_EIGHT)
    hit_t = np.unique(t_lab[near_found & (t_lab > 0)])
    hit_f = np.unique(f_lab[near_truth & (f_lab > 0)])
    recall = len(hit_t) / nt if nt else 1.0
    precision = len(hit_f) / nf if nf else 1.0
    return float(recall), float(precision)


def _pixel_scores(found: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    tp = float((found & truth).sum())
    n_true, n_found = float(truth.sum()), float(found.sum())
    return (tp / n_true if n_true else 1.0), (tp / n_found if n_found else 1.0)


@dataclass(frozen=True, eq=False)
class _Maps:
    rocks: list  # one bool map per rock height
    slope: np.ndarray  # deg, NaN where unknown
    steep: np.ndarray  # bool


def _maps(points, options: LandingOptions, window: int, base: int) -> _Maps:
    r = relief(points, window)
    with np.errstate(invalid="ignore"):
        rocks = [np.nan_to_num(r, nan=-np.inf) > h for h in options.rock_heights_m]
    slope = slope_map(points, base)
    steep = np.nan_to_num(slope, nan=0.0) > options.slope_deg
    return _Maps(rocks, slope, steep)


def _pixels(true_points, options: LandingOptions) -> tuple[int, int]:
    """(relief window, slope half-baseline) in pixels of the footprint in this view."""
    gsd = ground_sample_distance(true_points)
    window = max(3, round(options.footprint_m / gsd) | 1)  # odd, centred
    return window, max(1, round(options.footprint_m / (2 * gsd)))


def landing_hazard_maps(
    points: np.ndarray, true_points: np.ndarray, options: LandingOptions = LandingOptions()
) -> np.ndarray:
    """The hazard map the site choice reads (:func:`landing_scores`): rocks of the largest
    size or slopes above the limit, of ``points`` (a reconstruction's or the truth's), with
    the footprint in pixels of the true view. (rows, cols) bool."""
    window, base = _pixels(np.asarray(true_points, float), options)
    m = _maps(np.asarray(points, float), options, window, base)
    return m.rocks[int(np.argmax(options.rock_heights_m))] | m.steep


def landing_scores(
    recon_points: np.ndarray,
    true_points: np.ndarray,
    options: LandingOptions = LandingOptions(),
    *,
    centres: np.ndarray | None = None,
) -> dict[str, float]:
    """Landing scores of a reconstruction against the truth (module docstring).

    Parameters
    ----------
    recon_points, true_points : (rows, cols, 3) float
        World points of the same view's pixels (m, z up; NaN where unknown).
    options : LandingOptions
    centres : (m, 2) float, optional
        Candidate site centres (world x, y); default a grid of ``site_pitch_m`` over the truth.

    Returns
    -------
    dict
        Named by :func:`landing_metric_names` (heights in cm, slopes in deg in the names).
    """
    rec, tru = np.asarray(recon_points, float), np.asarray(true_points, float)
    if rec.shape != tru.shape or rec.ndim != 3 or rec.shape[-1] != 3:
        raise ValueError(f"points must be equal (rows, cols, 3) arrays: {rec.shape} {tru.shape}")
    window, base = _pixels(tru, options)
    known = np.isfinite(tru).all(-1)
    mt, mr = _maps(tru, options, window, base), _maps(rec, options, window, base)
    out: dict[str, float] = {}
    for h, ft, fr in zip(options.rock_heights_m, mt.rocks, mr.rocks, strict=True):
        recall, precision = object_scores(fr & known, ft & known)
        out[f"hazard_recall_rock_{_cm(h)}"] = recall
        out[f"hazard_precision_rock_{_cm(h)}"] = precision
    s = _deg(options.slope_deg)
    inside = known & np.isfinite(mt.slope)
    recall, precision = _pixel_scores(mr.steep & inside, mt.steep & inside)
    out[f"hazard_recall_slope_{s}"] = recall
    out[f"hazard_precision_slope_{s}"] = precision
    out.update(_site(rec, tru, mt, mr, options, centres))
    dz = rec[..., 2] - tru[..., 2]
    both = np.isfinite(dz) & known
    out["height_rms"] = float(np.sqrt(np.mean(dz[both] ** 2))) if both.any() else float("nan")
    ds = mr.slope - mt.slope
    ds = ds[np.isfinite(ds)]
    out["slope_rms_deg"] = float(np.sqrt(np.mean(ds**2))) if ds.size else float("nan")
    return out


def _site(rec, tru, mt: _Maps, mr: _Maps, options: LandingOptions, centres) -> dict[str, float]:
    r = options.site_radius_m
    if centres is None:
        site = SiteOptions(semi_axes_m=(r, r), pitch_m=options.site_pitch_m)
        centres = grid_sites(tru, site)
    c = np.asarray(centres, float).reshape(-1, 2)
    big = int(np.argmax(options.rock_heights_m))
    f_rec = site_fractions(rec, mr.rocks[big] | mr.steep, c, (r, r))
    f_true = site_fractions(tru, mt.rocks[big] | mt.steep, c, (r, r))
    order = np.where(np.isfinite(f_rec), f_rec, np.inf)  # unmeasured: never chosen first
    aim = np.nanmean(tru.reshape(-1, 3)[:, :2], axis=0)
    chosen = int(np.lexsort((np.linalg.norm(c - aim, axis=1), order))[0])
    called = bool(order[chosen] == 0.0)
    truly = bool(np.isfinite(f_true[chosen]) and f_true[chosen] == 0.0)
    return {
        "false_safe_site": float(called and not truly),
        "safe_site_called": float(called),
    }
