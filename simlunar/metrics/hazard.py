"""Landing hazards of a depth map: steep slopes and rocks, and how well a scan detects them.

A hazard map flags the guide-view pixels a lander must avoid: where the surface's slope over a
baseline of ``baseline_px`` pixels exceeds ``slope_deg``, or where it stands more than
``relief_m`` above the median height of a ``window_px`` neighbourhood (a rock). The same map
of a reconstructed depth and of the true depth gives pixel-wise detection precision and recall.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from simlunar.registry import Options, option, shared_option

__all__ = [
    "HAZARD_OPTIONS",
    "SLOPE_LIMIT",
    "HazardOptions",
    "check_odd_window",
    "detection_scores",
    "hazard_map",
]


#: options the hazard map and the landing question declare alike (name -> keywords of
#: :func:`simlunar.registry.option`, for :func:`simlunar.registry.shared_option`)
HAZARD_OPTIONS: dict[str, dict] = {
    "relief_m": dict(
        default=0.3, doc="largest safe height above the local median: rocks and boulders",
        unit="m", gt=0,
    ),
    "window_px": dict(default=15, doc="side of the median neighbourhood (odd)", unit="px", ge=3),
    "baseline_px": dict(
        default=2, doc="half the pixel step of the slope's central differences", unit="px", ge=1
    ),
}  # fmt: skip

#: doc, unit and bounds of the slope limit (its default is each class's own: 15 deg for a
#: hazard map, 12 deg for the landing question, :mod:`simlunar.metrics.safe_site`)
SLOPE_LIMIT: dict = dict(doc="largest safe slope over baseline_px", unit="deg", gt=0, lt=90)


def check_odd_window(options) -> None:
    """``ValueError`` unless ``options.window_px`` is odd (a centred median window)."""
    if int(options.window_px) % 2 == 0:
        raise ValueError(f"window_px must be odd, got {options.window_px!r}")


@dataclass(frozen=True)
class HazardOptions(Options):
    """What counts as a landing hazard."""

    slope_deg: float = option(15.0, **SLOPE_LIMIT)
    relief_m: float = shared_option(HAZARD_OPTIONS, "relief_m")
    window_px: int = shared_option(HAZARD_OPTIONS, "window_px")
    baseline_px: int = shared_option(HAZARD_OPTIONS, "baseline_px")

    def __post_init__(self):
        super().__post_init__()
        check_odd_window(self)


def _central(points: np.ndarray, step: int, axis: int) -> np.ndarray:
    """(points[i + step] - points[i - step]) along ``axis``; NaN within ``step`` of the border."""
    out = np.full(points.shape, np.nan)
    n = points.shape[axis]
    if n <= 2 * step:
        return out
    hi = np.take(points, range(2 * step, n), axis=axis)
    lo = np.take(points, range(0, n - 2 * step), axis=axis)
    idx = [slice(None)] * points.ndim
    idx[axis] = slice(step, n - step)
    out[tuple(idx)] = hi - lo
    return out


def hazard_map(points: np.ndarray, options: HazardOptions = HazardOptions()) -> np.ndarray:
    """Hazard flags of a surface seen in a view.

    Parameters
    ----------
    points : (rows, cols, 3) float
        World points (m, z up) of the view's pixels, e.g. ``camera.unproject_depth(depth)``;
        NaN where unknown.
    options : HazardOptions

    Returns
    -------
    (rows, cols) bool
        True where the slope or the relief exceeds its limit (False where unknown).
    """
    p = np.asarray(points, float)
    if p.ndim != 3 or p.shape[-1] != 3:
        raise ValueError(f"points must have shape (rows, cols, 3), got {p.shape}")
    s = int(options.baseline_px)
    normal = np.cross(_central(p, s, 1), _central(p, s, 0))
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.abs(normal[..., 2]) / np.linalg.norm(normal, axis=-1)
        steep = cos < np.cos(np.radians(options.slope_deg))
    z = p[..., 2]
    known = np.isfinite(z)
    filled = np.where(known, z, np.nanmedian(z) if known.any() else 0.0)
    rock = (z - ndimage.median_filter(filled, size=int(options.window_px))) > options.relief_m
    return (steep | rock) & known


def detection_scores(found: np.ndarray, truth: np.ndarray, mask=None) -> dict[str, float]:
    """Pixel-wise precision and recall of hazard flags ``found`` against ``truth``.

    Returns ``{"hazard_precision", "hazard_recall"}``: precision is 1 where nothing was flagged
    and recall 1 where there is no true hazard (nothing to miss), as is conventional.
    """
    found, truth = np.asarray(found, bool), np.asarray(truth, bool)
    if mask is not None:
        found, truth = found & mask, truth & mask
    tp = float((found & truth).sum())
    flagged, actual = float(found.sum()), float(truth.sum())
    return {
        "hazard_precision": tp / flagged if flagged else 1.0,
        "hazard_recall": tp / actual if actual else 1.0,
    }
