"""The landing question: is the site chosen from the reconstruction truly safe?

A lander picks one of several candidate landing ellipses from what it measured. Each candidate
is judged by the hazard map of :mod:`simlunar.metrics.hazard` inside it: its hazard fraction is
the share of its (known) pixels flagged as too steep or too rocky. The lander chooses the
candidate with the smallest *reconstructed* hazard fraction (ties: the one nearest the aim
point, the view's centre); the choice is **truly safe** when the *true* hazard fraction of that
candidate is at most ``max_hazard_fraction`` (default 0: not one hazard pixel in the ellipse).
Over trials and terrain seeds the mean of ``safe_site`` is the probability that the chosen site
is safe. ``safe_site_precision`` is the share of the candidates the reconstruction calls safe
that are truly safe (1 when it calls none safe), ``safe_sites_available`` the share of
candidates truly safe (what a perfect sensor could choose from).

Thresholds (:class:`SiteOptions`): rocks higher than 0.3 m (the ALHAT hazard-detection
requirement, rocks > 30 cm: Amzajerdian et al. 2015, AIAA GNC) and slopes steeper than 12 deg
(the Apollo lunar module's landing-slope limit as usually quoted: an **assumption**, not
verified here; ALHAT's detection requirement of 5 deg slopes is stricter). The ellipse size
(4 m semi-axes: a lander's footprint plus terminal guidance dispersion) is an assumption too.
Membership of a pixel in an ellipse is by its ground (x, y): the reconstruction's points for the
choice, the true points for the judgement.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.metrics.hazard import (
    HAZARD_OPTIONS,
    SLOPE_LIMIT,
    HazardOptions,
    check_odd_window,
    hazard_map,
)
from simlunar.registry import Options, option, shared_option

__all__ = ["SiteOptions", "grid_sites", "safe_site_scores", "site_fractions"]


@dataclass(frozen=True)
class SiteOptions(Options):
    """Safe-site thresholds and candidates (module docstring for sources); ``window_px`` and
    ``baseline_px`` as for :class:`~simlunar.metrics.hazard.HazardOptions`."""

    slope_deg: float = option(12.0, **SLOPE_LIMIT)
    rock_height_m: float = shared_option(HAZARD_OPTIONS, "relief_m")
    window_px: int = shared_option(HAZARD_OPTIONS, "window_px")
    baseline_px: int = shared_option(HAZARD_OPTIONS, "baseline_px")
    semi_axes_m: tuple = option(
        (4.0, 4.0), doc="semi-axes of a landing ellipse along world x and y (two > 0)", unit="m"
    )
    pitch_m: float = option(
        8.0, doc="spacing of the candidate centres on a grid over the view", unit="m", gt=0
    )
    max_hazard_fraction: float = option(
        0.0, doc="a site is safe when at most this share of its pixels is hazardous", ge=0, lt=1
    )

    def __post_init__(self):
        super().__post_init__()
        check_odd_window(self)
        a = np.asarray(self.semi_axes_m, float)
        if a.shape != (2,) or not np.all(np.isfinite(a)) or a.min() <= 0:
            raise ValueError(f"semi_axes_m must be two lengths > 0, got {self.semi_axes_m}")

    @property
    def hazard(self) -> HazardOptions:
        """The hazard map's options."""
        return HazardOptions(self.slope_deg, self.rock_height_m, self.window_px, self.baseline_px)


def grid_sites(points: np.ndarray, options: SiteOptions) -> np.ndarray:
    """Candidate ellipse centres (m, 2) (world x, y, m) on a grid of ``pitch_m`` whose ellipses
    lie inside the known ground of ``points`` (rows, cols, 3)'s bounding box."""
    p = np.asarray(points, float).reshape(-1, 3)
    p = p[np.isfinite(p).all(axis=1)]
    if len(p) == 0:
        raise ValueError("grid_sites: no known point in the view")
    a = np.asarray(options.semi_axes_m, float)
    lo, hi = p[:, :2].min(axis=0) + a, p[:, :2].max(axis=0) - a
    if np.any(hi < lo):
        raise ValueError(f"the view ({np.ptp(p[:, :2], axis=0)} m) is smaller than an ellipse")
    n = np.floor((hi - lo) / options.pitch_m).astype(int) + 1
    off = lo + 0.5 * ((hi - lo) - (n - 1) * options.pitch_m)  # centred in the view
    gx = off[0] + options.pitch_m * np.arange(n[0])
    gy = off[1] + options.pitch_m * np.arange(n[1])
    return np.stack(np.meshgrid(gx, gy, indexing="ij"), -1).reshape(-1, 2)


def site_fractions(
    points: np.ndarray, hazards: np.ndarray, centres: np.ndarray, semi_axes_m
) -> np.ndarray:
    """Hazard fraction (m,) of each ellipse: flagged / known pixels whose ground (x, y) lies
    inside it (NaN for an ellipse with no known pixel).

    Parameters
    ----------
    points : (rows, cols, 3) float
        World points of the view's pixels (NaN where unknown).
    hazards : (rows, cols) bool
    centres : (m, 2) float
        Ellipse centres (world x, y, m).
    semi_axes_m : (2,) float
        Semi-axes along x and y (m).
    """
    p = np.asarray(points, float).reshape(-1, 3)
    h = np.asarray(hazards, bool).reshape(-1)
    if h.size != len(p):
        raise ValueError(f"hazards {np.shape(hazards)} and points {np.shape(points)} differ")
    known = np.isfinite(p).all(axis=1)
    xy, h = p[known, :2], h[known]
    a = np.asarray(semi_axes_m, float)
    c = np.asarray(centres, float).reshape(-1, 2)
    out = np.full(len(c), np.nan)
    for i, ci in enumerate(c):
        inside = (((xy - ci) / a) ** 2).sum(axis=1) <= 1.0
        if inside.any():
            out[i] = h[inside].mean()
    return out


def safe_site_scores(
    recon_points: np.ndarray,
    true_points: np.ndarray,
    options: SiteOptions = SiteOptions(),
    *,
    centres: np.ndarray | None = None,
) -> dict[str, float]:
    """Whether the site chosen from the reconstruction is truly safe (module docstring).

    Parameters
    ----------
    recon_points, true_points : (rows, cols, 3) float
        The view's reconstructed and true world points (m; NaN where unknown).
    options : SiteOptions
    centres : (m, 2) float or None
        Candidate ellipse centres (world x, y, m); None = :func:`grid_sites` of the truth's
        view.

    Returns
    -------
    dict
        ``safe_site`` (1.0 if the chosen site is truly safe, else 0.0), ``safe_site_precision``
        and ``safe_sites_available``.
    """
    c = grid_sites(true_points, options) if centres is None else np.asarray(centres, float)
    if len(c) == 0:
        raise ValueError("safe_site_scores: no candidate site")
    hz = options.hazard
    f_rec = site_fractions(recon_points, hazard_map(recon_points, hz), c, options.semi_axes_m)
    f_true = site_fractions(true_points, hazard_map(true_points, hz), c, options.semi_axes_m)
    tol = options.max_hazard_fraction
    rec = np.where(np.isfinite(f_rec), f_rec, np.inf)  # unmeasured: never chosen first
    aim = np.nanmean(np.asarray(true_points, float).reshape(-1, 3)[:, :2], axis=0)
    dist = np.linalg.norm(c - aim, axis=1)
    chosen = int(np.lexsort((dist, rec))[0])
    truly = np.isfinite(f_true) & (f_true <= tol + 1e-12)
    called = np.isfinite(f_rec) & (f_rec <= tol + 1e-12)
    return {
        "safe_site": float(truly[chosen]),
        "safe_site_precision": float(truly[called].mean()) if called.any() else 1.0,
        "safe_sites_available": float(truly.mean()),
    }
