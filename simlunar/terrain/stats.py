"""Roughness statistics of a height grid, comparable to lunar measurements (NumPy only).

Definitions (as in the LOLA and LROC NAC DTM roughness literature, see docs/terrain.md):

* differences at baseline ``L = k * spacing`` along both grid axes,
  ``dx = z(x + L, y) - z(x, y)`` and ``dy = z(x, y + L) - z(x, y)`` (NaN pairs skipped);
* RMS deviation (deviogram) ``nu(L) = sqrt((mean dx^2 + mean dy^2) / 2)``, the RMS height
  change per axis;
* bidirectional slope at a point ``tan(theta) = sqrt((dx / L)^2 + (dy / L)^2)`` (the gradient
  magnitude from two orthogonal baselines); its RMS is ``sqrt(2) nu(L) / L`` and its median is
  reported too, both in degrees;
* Hurst exponent ``H``: the least-squares slope of ``log nu(L)`` against ``log L``
  (``nu(L) ~ L^H``) over the baselines given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Roughness", "default_baselines", "feature_densities", "roughness", "terrain_report"]


@dataclass(frozen=True)
class Roughness:
    """Roughness of a height grid at several baselines.

    Attributes
    ----------
    baselines_m : tuple of float
    nu_m : tuple of float
        RMS deviation per axis at each baseline (m).
    rms_slope_deg : tuple of float
        RMS bidirectional slope ``atan(sqrt(2) nu / L)`` (degrees).
    median_slope_deg : tuple of float
        Median bidirectional slope (degrees).
    hurst : float
        Slope of log nu against log L over all baselines.
    """

    baselines_m: tuple[float, ...]
    nu_m: tuple[float, ...]
    rms_slope_deg: tuple[float, ...]
    median_slope_deg: tuple[float, ...]
    hurst: float


def default_baselines(shape: tuple[int, int], spacing: float, *, count: int = 5) -> list[float]:
    """Baselines ``spacing * 2^i`` (i = 0, 1, ...), at most ``count``, up to a quarter grid."""
    n_max = max(1, min(shape) // 4)
    ks = [2**i for i in range(count) if 2**i <= n_max]
    return [k * spacing for k in ks]


def _diffs(z: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """dx, dy at lag k cells at the points (r >= k, c < cols - k) where both exist."""
    dx = z[k:, k:] - z[k:, :-k]
    # rows run to -y: z(x, y + L) is k rows up, at row r - k
    dy = z[:-k, :-k] - z[k:, :-k]
    return dx, dy


def roughness(heights, spacing: float, *, baselines_m=None) -> Roughness:
    """RMS deviation, bidirectional slopes and Hurst exponent of a height grid.

    Parameters
    ----------
    heights : (rows, cols) array, metres; NaN = nodata (pairs touching it are skipped)
    spacing : float
        Cell size (m).
    baselines_m : sequence of float, optional
        Baselines in metres, each a whole number of cells; default :func:`default_baselines`.

    Returns
    -------
    Roughness

    Raises
    ------
    ValueError
        A baseline that is not a positive whole number of cells or leaves no pair, fewer than
        two baselines for the Hurst fit, a non-2-D grid.
    """
    z = np.asarray(heights, np.float64)
    if z.ndim != 2:
        raise ValueError(f"heights must be 2-D, got shape {z.shape}")
    if not spacing > 0:
        raise ValueError(f"spacing must be positive, got {spacing}")
    bl = list(default_baselines(z.shape, spacing) if baselines_m is None else baselines_m)
    if len(bl) < 2:
        raise ValueError(f"need at least two baselines for the Hurst fit, got {bl}")
    nus, rms, med = [], [], []
    for L in bl:
        k = round(L / spacing)
        if k < 1 or not np.isclose(k * spacing, L, rtol=1e-6):
            raise ValueError(f"baseline {L} m is not a whole number (>= 1) of cells of {spacing} m")
        if k >= min(z.shape):
            raise ValueError(f"baseline {L} m ({k} cells) does not fit the {z.shape} grid")
        dx, dy = _diffs(z, k)
        ok = np.isfinite(dx) & np.isfinite(dy)
        if ok.all():  # no nodata: skip the masked copies
            dx, dy = dx.ravel(), dy.ravel()
        elif ok.any():
            dx, dy = dx[ok], dy[ok]
        else:
            raise ValueError(f"baseline {L} m: no pair of valid heights")
        nu = np.sqrt(0.5 * (np.dot(dx, dx) + np.dot(dy, dy)) / dx.size)
        slope = np.hypot(dx, dy) / (k * spacing)
        nus.append(float(nu))
        rms.append(float(np.degrees(np.arctan(np.sqrt(2.0) * nu / (k * spacing)))))
        med.append(float(np.degrees(np.arctan(np.median(slope)))))
    L = np.array([round(b / spacing) * spacing for b in bl])
    nu = np.array(nus)
    if np.any(nu <= 0):
        hurst = float("nan")  # a flat grid has no roughness to scale
    else:
        hurst = float(np.polyfit(np.log(L), np.log(nu), 1)[0])
    return Roughness(tuple(float(v) for v in L), tuple(nus), tuple(rms), tuple(med), hurst)


def feature_densities(
    diameters_m, area_m2: float, *, thresholds_m, per_m2: float = 1.0
) -> dict[float, float]:
    """Cumulative density of features (craters or rocks) with diameter >= each threshold.

    Parameters
    ----------
    diameters_m : sequence of float
    area_m2 : float
        Area the features were counted on.
    thresholds_m : sequence of float
    per_m2 : float
        Unit area of the result: 1 (per m^2), 100 (per 100 m^2, Surveyor counts), 1e6 (per km^2).

    Returns
    -------
    dict threshold -> count per ``per_m2`` square metres.
    """
    if not area_m2 > 0:
        raise ValueError(f"area_m2 must be positive, got {area_m2}")
    d = np.asarray(list(diameters_m), np.float64)
    return {float(t): float(np.sum(d >= t)) / area_m2 * per_m2 for t in thresholds_m}


def terrain_report(terrain, *, craters=(), rocks=(), baselines_m=None) -> list[str]:
    """Lines of text: roughness at each baseline, Hurst exponent, crater and rock densities.

    ``craters``/``rocks`` are the placed features (objects with ``diameter``), e.g. from
    :class:`~simlunar.terrain.TerrainResult`; without them the densities are reported unknown.
    Craters are counted per km^2 with D >= 5, 25, 50 cells, rocks per 100 m^2 (the Surveyor
    convention) with D >= 0.5, 2.5, 5 cells; the area is that of the valid cells.
    """
    r = roughness(terrain.heights, terrain.spacing, baselines_m=baselines_m)
    lines = [f"{'baseline (m)':>13} {'nu (m)':>9} {'RMS slope':>10} {'median slope':>13}"]
    for L, nu, s, m in zip(r.baselines_m, r.nu_m, r.rms_slope_deg, r.median_slope_deg):
        lines.append(f"{L:13.4g} {nu:9.4g} {s:9.2f}° {m:12.2f}°")
    lines.append(
        f"Hurst exponent H = {r.hurst:.3f} (fit of log nu vs log L, "
        f"{r.baselines_m[0]:.4g}-{r.baselines_m[-1]:.4g} m)"
    )
    xmin, xmax, ymin, ymax = terrain.extent
    area = (xmax - xmin) * (ymax - ymin) * float(np.mean(~terrain.nodata))
    if len(craters) or len(rocks):
        # thresholds in cells (5, 25, 50 for craters; 0.5, 2.5, 5 for rocks): 1, 5, 10 m and
        # 0.1, 0.5, 1 m on the 0.2 m aerial grids
        sp = terrain.spacing
        ct = tuple(float(f"{m * sp:.4g}") for m in (5, 25, 50))
        rt = tuple(float(f"{m * sp:.4g}") for m in (0.5, 2.5, 5))
        cd = feature_densities([c.diameter for c in craters], area, thresholds_m=ct, per_m2=1e6)
        rd = feature_densities([k.diameter for k in rocks], area, thresholds_m=rt, per_m2=100.0)
        lines.append(
            "craters per km^2: " + ", ".join(f"D >= {t:g} m: {v:.4g}" for t, v in cd.items())
        )
        lines.append(
            "rocks per 100 m^2: " + ", ".join(f"D >= {t:g} m: {v:.4g}" for t, v in rd.items())
        )
    else:
        lines.append("crater and rock densities: unknown (no placed features for this grid)")
    return lines
