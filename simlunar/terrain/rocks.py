"""Rocks: clustered placement and irregular, half-buried shapes that raise the DEM.

Placement is a Thomas-type cluster process conditioned on the total count: a fraction of the
rocks scatter with a Gaussian offset around uniformly placed parent centres (rocks cluster around
the craters that excavated them), the rest are uniform. Offsets wrap around the placement extent so
the mean density stays uniform.

Shape: the upper part of a flattened ellipsoid whose outline is perturbed by random low-order
angular harmonics (k = 2..4), i.e. an irregular boulder partly buried in regolith. Exposed height
is ``D * height_ratio`` with ``height_ratio`` uniform in ``[0.25, 0.5]`` (a half-buried sphere
would be 0.5). A rock raises the DEM (``max`` with its top surface, seated on the lowest ground of
its footprint) and has its own albedo factor.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from simlunar.terrain._window import feature_window

__all__ = ["Rock", "place_rocks", "stamp_rocks"]

_HARMONICS = (2, 3, 4)


@dataclass(frozen=True)
class Rock:
    """One placed rock (world coordinates and sizes in metres)."""

    x: float
    y: float
    diameter: float
    height: float
    elongation: float  # minor / major axis ratio
    orientation: float  # radians, major axis from +x
    albedo_factor: float

    def to_dict(self) -> dict:
        return {k: float(v) for k, v in asdict(self).items()}


def place_rocks(
    diameters: np.ndarray,
    *,
    extent: tuple[float, float, float, float],
    cluster_fraction: float,
    cluster_radius_m: float,
    mean_per_cluster: float,
    albedo_contrast: float,
    rng=None,
) -> list[Rock]:
    """Positions, shapes and albedo factors for given rock diameters.

    Parameters
    ----------
    diameters : (n,) float array, metres
    extent : (xmin, xmax, ymin, ymax) placement area, metres
    cluster_fraction : float in [0, 1]
        Share of rocks placed in clusters.
    cluster_radius_m : float
        Standard deviation of the Gaussian offset from the cluster centre (m).
    mean_per_cluster : float
        Mean number of rocks per cluster (sets the number of parents).
    albedo_contrast : float
        Rock albedo factor is ``1 + albedo_contrast * (1 + 0.3 N(0, 1))``; rocks are
        slightly brighter than mature soil for a positive value.
    rng : seed or Generator
    """
    gen = np.random.default_rng(rng)
    d = np.asarray(diameters, dtype=np.float64)
    n = d.size
    xmin, xmax, ymin, ymax = extent
    w, h = xmax - xmin, ymax - ymin
    x = gen.uniform(xmin, xmax, n)
    y = gen.uniform(ymin, ymax, n)
    clustered = gen.random(n) < cluster_fraction
    m = int(clustered.sum())
    if m:
        n_par = max(1, round(m / mean_per_cluster))
        px = gen.uniform(xmin, xmax, n_par)
        py = gen.uniform(ymin, ymax, n_par)
        which = gen.integers(0, n_par, m)
        x[clustered] = xmin + np.mod(px[which] + gen.normal(0, cluster_radius_m, m) - xmin, w)
        y[clustered] = ymin + np.mod(py[which] + gen.normal(0, cluster_radius_m, m) - ymin, h)
    hr = gen.uniform(0.25, 0.5, n)
    el = gen.uniform(0.6, 1.0, n)
    ori = gen.uniform(0, np.pi, n)
    alb = 1.0 + albedo_contrast * (1.0 + 0.3 * gen.standard_normal(n))
    return [
        Rock(
            float(x[i]),
            float(y[i]),
            float(d[i]),
            float(d[i] * hr[i]),
            float(el[i]),
            float(ori[i]),
            float(max(alb[i], 0.2)),
        )
        for i in range(n)
    ]


def stamp_rocks(
    heights: np.ndarray,
    albedo_factor: np.ndarray,
    rocks: list[Rock],
    *,
    spacing: float,
    origin: tuple[float, float],
    rng=None,
) -> None:
    """Raise ``heights`` by each rock's top surface and set its albedo factor, in place.

    Each rock touches only its bounding window. ``rng`` draws the outline harmonics.
    """
    gen = np.random.default_rng(rng)
    nh = len(_HARMONICS)
    amps = gen.uniform(0.0, 0.12, (len(rocks), nh))
    phases = gen.uniform(0, 2 * np.pi, (len(rocks), nh))
    ks = np.array(_HARMONICS, dtype=np.float64)
    for i, rk in enumerate(rocks):
        a = rk.diameter / 2.0
        ext = a * 1.4  # outline perturbation is at most +36 %
        w = feature_window(rk.x, rk.y, ext, heights.shape, spacing, origin)
        if w is None:
            continue
        rs, cs, dx, dy = w
        dx, dy = dx[None, :], dy[:, None]
        co, si = np.cos(rk.orientation), np.sin(rk.orientation)
        u = (dx * co + dy * si) / a
        v = (-dx * si + dy * co) / (a * rk.elongation)
        theta = np.arctan2(v, u)
        rho = 1.0 + (
            amps[i][:, None, None] * np.cos(ks[:, None, None] * theta + phases[i][:, None, None])
        ).sum(0)
        q = 1.0 - (u * u + v * v) / (rho * rho)
        foot = q > 0
        if not np.any(foot):
            continue
        win = heights[rs, cs]
        top = win[foot].min() + rk.height * np.sqrt(np.where(foot, q, 0.0))
        np.maximum(win, np.where(foot, top, -np.inf), out=win)
        albedo_factor[rs, cs][foot] = rk.albedo_factor
