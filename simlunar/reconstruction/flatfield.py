"""Flat-fielding the co-located frame from the rig's geometry (no truth: the samples only).

A real co-located frame is lit by a flash on the rig: a point emitter a baseline from the
camera with inverse-square falloff, incidence and a ``cos^n`` beam
(:func:`simlunar.geometry.point_irradiance`). Across an aerial view from 50 m that falls to
0.35-0.39 of the centre at the corners, and the ratio ``sun / flat`` then carries the falloff
instead of albedo alone: the slope read from it is wrong at every scale. The falloff follows
from the rig's pose (:class:`FlashGeometry`, carried by the
:class:`~simlunar.reconstruction.Guide`) and the surface known so far: the range samples'
linear reconstruction. :func:`flat_field` divides the frame by the irradiance the flash gives
that surface, so what stays is albedo times the flash's shading of the detail the samples do
not resolve (the part an ideal co-located light at infinity would show too).

Coordinates are the guide's grid: ``(row, col, up)`` in metres with rows and columns at
``spacing`` m per cell and ``up`` out of the surface. Sample values are depths (distance from
the camera's image plane along a nadir view: up = -depth) or heights (up = height).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from simlunar.reconstruction.integrate import central_gradient
from simlunar.registry import Options, option

__all__ = ["FlashGeometry", "flash_falloff", "flash_relief_gain", "flat_field"]


@dataclass(frozen=True)
class FlashGeometry(Options):
    """Where the flash of the co-located frame is, in the guide's grid (nadir view).

    ``row``, ``col`` are the light's grid position in cells (cell (r, c) at (r, c)),
    ``level`` its value in the samples' units (its depth below the camera's image plane, 0 for
    a light in that plane; or its height for height samples).
    """

    row: float = option(0.0, doc="grid row of the light (cells)")
    col: float = option(0.0, doc="grid column of the light (cells)")
    level: float = option(0.0, doc="the light's depth (or height) in the samples' units", unit="m")
    axis_row: float = option(0.0, doc="beam axis, row component (grid frame)")
    axis_col: float = option(0.0, doc="beam axis, column component (grid frame)")
    axis_up: float = option(-1.0, doc="beam axis, up component (grid frame; -1: straight down)")
    beam_exponent: float = option(0.0, doc="n of the cos^n beam", ge=0, le=1000)
    cutoff: float = option(np.pi / 2, doc="half-angle of the beam", unit="rad", gt=0, le=np.pi / 2)
    values: str = option("depth", doc="what the sample values are", choices=("depth", "height"))

    def __post_init__(self):
        super().__post_init__()
        if np.hypot(np.hypot(self.axis_row, self.axis_col), self.axis_up) == 0:
            raise ValueError("the beam axis must not be zero")

    @property
    def axis(self) -> np.ndarray:
        a = np.array([self.axis_row, self.axis_col, self.axis_up], dtype=np.float64)
        return a / np.linalg.norm(a)


def flash_falloff(
    values, geometry: FlashGeometry, *, spacing: float = 1.0, slopes=None
) -> np.ndarray:
    """Relative irradiance (max 1) the flash gives a surface of per-cell ``values``.

    Parameters
    ----------
    values : ndarray, shape (rows, cols)
        The surface (depths or heights, as ``geometry.values``), e.g. the samples' linear
        reconstruction.
    geometry : FlashGeometry
    spacing : float
        Cell size (m).
    slopes : tuple of ndarray, optional
        ``integrate.central_gradient(values)`` when already made (the same to the bit).

    Returns
    -------
    ndarray, shape (rows, cols)
        ``cos^n(theta) cos(i) / d^2`` over its maximum (0 outside the beam or facing away).
    """
    v = np.asarray(values, dtype=np.float64)
    if v.ndim != 2:
        raise ValueError(f"values must be a (rows, cols) grid, got shape {v.shape}")
    sign = -1.0 if geometry.values == "depth" else 1.0
    up = sign * v
    if slopes is None:
        gr, gc = central_gradient(up)
    else:  # central differences of -v are those of v negated, exactly
        gr, gc = sign * slopes[0], sign * slopes[1]
    a = geometry.axis
    e = _falloff(
        up, gr, gc, float(spacing), geometry.row * spacing, geometry.col * spacing,
        sign * geometry.level, a[0], a[1], a[2], float(geometry.beam_exponent),
        float(np.cos(geometry.cutoff)),
    )  # fmt: skip
    top = float(e.max())
    if not top > 0:
        raise ValueError("the flash lights no cell of the surface (check its geometry)")
    e /= top
    return e


@numba.njit(cache=True, nogil=True)
def _falloff(up, gr, gc, s, pr, pc, pu, ar, ac, au, n, cos_cut):  # pragma: no cover - compiled
    """:func:`simlunar.geometry.point_irradiance` at ``I0 = 1`` of the cells (r s, c s, up)
    with normals (-gr / s, -gc / s, 1), in one pass (tests/pipeline/test_guide.py checks it
    against the NumPy function on the rendered light's world frame)."""
    rows, cols = up.shape
    out = np.zeros((rows, cols))
    for r in range(rows):
        for c in range(cols):
            dr = pr - r * s
            dc = pc - c * s
            du = pu - up[r, c]
            d2 = dr * dr + dc * dc + du * du
            d = np.sqrt(d2)
            mr = -gr[r, c] / s
            mc = -gc[r, c] / s
            m = np.sqrt(mr * mr + mc * mc + 1.0)
            cos_i = (dr * mr + dc * mc + du) / (d * m)
            cos_t = -(dr * ar + dc * ac + du * au) / d
            if cos_i <= 0.0 or cos_t <= 0.0 or cos_t < cos_cut - 1e-12:
                continue
            out[r, c] = cos_t**n * cos_i / d2
    return out


def flat_field(
    flat, values, geometry: FlashGeometry, *, spacing: float = 1.0, slopes=None
) -> np.ndarray:
    """``flat`` divided by :func:`flash_falloff` of ``values`` (0 where the flash gives less
    than 1e-3 of its maximum: out of the beam, or facing away); ``slopes``: as there."""
    f = flash_falloff(values, geometry, spacing=spacing, slopes=slopes)
    out = np.asarray(flat, dtype=np.float64) / np.maximum(f, 1e-3)
    out[f < 1e-3] = 0.0
    return out


def flash_relief_gain(values, geometry: FlashGeometry, *, spacing: float = 1.0) -> np.ndarray:
    """How a flat-fielded flash frame still answers the relief ``values`` do not carry.

    :func:`flat_field` divides the frame by the incidence ``L = l . n`` the flash gives the
    surface ``values`` (``l`` the unit vector to the light, ``n = (-grad up, 1)``); the true
    surface's steeper or flatter detail leaves ``L_lin / L`` in the frame, which to first
    order in the values' detail slope ``G_d`` (per metre) is ``1 + k . G_d`` with
    ``k = sign l_h / L_lin`` (``sign`` -1 for depths, +1 for heights; ``l_h`` the light's
    horizontal (row, col) components). A ratio ``sun / flat`` then reads
    ``a + b . G_lin + (b + a k) . G_d`` instead of ``a + b . G``: the light's tilt, up to
    ~43 deg at the corners of an aerial view from 50 m, changes the slope's gain and direction
    there. ``k`` is 0 for a light straight above (the ideal co-located light).

    Returns
    -------
    ndarray, shape (2, rows, cols)
        ``k`` (row and column components, per unit of slope); 0 where the flash does not
        light the surface.
    """
    v = np.asarray(values, dtype=np.float64)
    if v.ndim != 2:
        raise ValueError(f"values must be a (rows, cols) grid, got shape {v.shape}")
    sign = -1.0 if geometry.values == "depth" else 1.0
    up = sign * v
    gr, gc = central_gradient(up)
    return _relief_gain(
        up, gr, gc, float(spacing), geometry.row * spacing, geometry.col * spacing,
        sign * geometry.level, sign,
    )  # fmt: skip


@numba.njit(cache=True, nogil=True)
def _relief_gain(up, gr, gc, s, pr, pc, pu, sign):  # pragma: no cover - compiled
    """``k = sign (dr, dc) / (dr mr + dc mc + du)`` per cell, ``(dr, dc, du)`` the light's
    offset and ``(mr, mc, 1)`` the unnormalised normal (the distance cancels)."""
    rows, cols = up.shape
    out = np.zeros((2, rows, cols))
    for r in range(rows):
        for c in range(cols):
            dr = pr - r * s
            dc = pc - c * s
            du = pu - up[r, c]
            den = dr * (-gr[r, c] / s) + dc * (-gc[r, c] / s) + du
            if den <= 0.0:
                continue
            out[0, r, c] = sign * dr / den
            out[1, r, c] = sign * dc / den
    return out
