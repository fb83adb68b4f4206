"""Irradiance of a point emitter with a beam profile (NumPy only).

A flash or flood light is a point source at ``position`` whose radiant intensity falls off
from its beam axis as ``I(theta) = I0 cos^n(theta)`` (``theta`` the angle from the axis, ``n``
the beam exponent; ``n = 0`` an isotropic source), with no light beyond ``cutoff``. A surface
point ``x`` with unit normal ``m`` at distance ``d = |position - x|`` receives

    E(x) = I0 cos^n(theta) max(m . l, 0) / d^2,     l = (position - x) / d,

the inverse-square law times the cosine of incidence (e.g. McCluney, *Introduction to
Radiometry and Photometry*, 2nd ed., eq. 2.21). The power a cos^n beam sends into the
hemisphere around its axis is ``P = 2 pi I0 / (n + 1)`` (the integral of ``cos^n theta`` over
the hemisphere), so a flash of energy ``Q`` (J) spread evenly over an exposure of ``t``
seconds has ``I0 = Q (n + 1) / (2 pi t)`` (:func:`beam_intensity`), when the cutoff leaves
the beam whole.

The render (:class:`simlunar.render.lights.FlashLight`) and the reconstructions'
flat-fielding (:mod:`simlunar.reconstruction.flatfield`) both evaluate this one function.
"""

from __future__ import annotations

import numpy as np

__all__ = ["beam_intensity", "beam_profile", "point_irradiance"]


def beam_intensity(energy: float, exposure: float, beam_exponent: float) -> float:
    """On-axis radiant intensity (W/sr) of a ``cos^n`` beam of ``energy`` J per flash emitted
    evenly during an exposure of ``exposure`` s: ``I0 = Q (n + 1) / (2 pi t)``."""
    if not (energy >= 0 and exposure > 0 and beam_exponent >= 0):
        raise ValueError(
            f"need energy >= 0, exposure > 0 and beam_exponent >= 0, got {energy}, {exposure}, "
            f"{beam_exponent}"
        )
    return float(energy) * (float(beam_exponent) + 1.0) / (2.0 * np.pi * float(exposure))


def beam_profile(cos_theta, beam_exponent: float, cutoff: float = np.pi / 2) -> np.ndarray:
    """Relative intensity ``cos^n(theta)`` at ``cos_theta`` (0 beyond ``cutoff`` rad)."""
    c = np.asarray(cos_theta, dtype=np.float64)
    inside = c >= np.cos(cutoff) - 1e-12
    return np.where(inside & (c > 0), np.maximum(c, 0.0) ** float(beam_exponent), 0.0)


def point_irradiance(
    points,
    normals,
    *,
    position,
    axis,
    intensity: float = 1.0,
    beam_exponent: float = 0.0,
    cutoff: float = np.pi / 2,
) -> np.ndarray:
    """Irradiance (W/m^2 for ``intensity`` in W/sr) a point emitter gives surface points.

    Parameters
    ----------
    points : array_like, shape (..., 3)
        Surface points (m).
    normals : array_like, shape (..., 3)
        Their normals (normalised here).
    position : array_like, shape (3,)
        The emitter (m), in the points' frame.
    axis : array_like, shape (3,)
        The beam axis (normalised here), pointing away from the emitter.
    intensity : float
        On-axis radiant intensity ``I0`` (W/sr).
    beam_exponent : float
        ``n`` of the ``cos^n`` beam (0: isotropic).
    cutoff : float
        Half-angle of the beam (rad); no light beyond it.

    Returns
    -------
    ndarray, shape (...)
        ``I0 cos^n(theta) max(m . l, 0) / d^2`` (no occlusion: a cast shadow is the render's).
    """
    x = np.asarray(points, dtype=np.float64)
    m = np.asarray(normals, dtype=np.float64)
    m = m / np.linalg.norm(m, axis=-1, keepdims=True)
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    to_light = np.asarray(position, dtype=np.float64) - x
    d2 = np.einsum("...i,...i->...", to_light, to_light)
    d = np.sqrt(d2)
    if np.any(d == 0):
        raise ValueError("a surface point coincides with the emitter")
    l_dir = to_light / d[..., None]
    cos_i = np.maximum(np.einsum("...i,...i->...", l_dir, m), 0.0)
    cos_t = -(l_dir @ a)
    return float(intensity) * beam_profile(cos_t, beam_exponent, cutoff) * cos_i / d2
