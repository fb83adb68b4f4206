"""Mitsuba ``load_dict`` entries for simlunar's BSDF specs.

:func:`bsdf_dict` turns a spec of :mod:`simlunar.render.materials` into the dict of the
built-in ``diffuse`` or of simlunar's plugins ``oren_nayar`` and ``hapke``. The plugins live in
:mod:`simlunar.render.plugins` (one module each, with its parameter table) and are registered
by :func:`simlunar.render.backend.init` once the variant is set. Importing this module never
imports Mitsuba.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from simlunar.render.materials import HapkeBSDF, LambertBSDF, OrenNayarBSDF
from simlunar.render.mesh import grid_texture
from simlunar.render.plugins.hapke import HAPKE_TABLE_SIZE

__all__ = ["HAPKE_TABLE_SIZE", "bsdf_dict"]


def _texture(reflectance: Any) -> Any:
    if isinstance(reflectance, (int, float, np.floating, np.integer)):
        v = float(reflectance)
        if not (math.isfinite(v) and 0.0 <= v <= 1.0):
            raise ValueError(f"reflectance must be in [0, 1], got {reflectance!r}")
        return v
    return reflectance


def bsdf_dict(spec: LambertBSDF | OrenNayarBSDF | HapkeBSDF, reflectance: Any = 0.5) -> dict:
    """Mitsuba ``load_dict`` entry for a BSDF spec.

    Parameters
    ----------
    spec : LambertBSDF, OrenNayarBSDF or HapkeBSDF
        From :func:`simlunar.render.materials.make_bsdf`.
    reflectance : float, dict or mitsuba Texture
        The albedo: a constant in [0, 1], a Mitsuba texture dict (e.g. a ``bitmap`` of the
        terrain albedo grid) or a loaded texture. Lambert: diffuse reflectance;
        Oren-Nayar: facet albedo; Hapke: normal albedo (ignored when ``spec.w`` is set).
        An ``OrenNayarBSDF`` with a ``sigma_map`` gets that grid as a ``bitmap`` ``sigma``
        texture with the same addressing as a grid albedo (texel (r, c) at terrain vertex
        (r, c), nearest filter: :func:`simlunar.render.mesh.grid_texture`).

    Returns
    -------
    dict
        ``{"type": "diffuse" | "oren_nayar" | "hapke", ...}``; the plugins are registered by
        :func:`simlunar.render.backend.init`.
    """
    tex = _texture(reflectance)
    if isinstance(spec, LambertBSDF):
        return {"type": "diffuse", "reflectance": tex}
    if isinstance(spec, OrenNayarBSDF):
        sigma: Any = spec.sigma
        if spec.sigma_map is not None:
            sigma = grid_texture(spec.sigma_map)
        return {"type": "oren_nayar", "reflectance": tex, "sigma": sigma, "model": spec.model}
    if isinstance(spec, HapkeBSDF):
        d = {
            "type": "hapke",
            "b": spec.b,
            "c": spec.c,
            "B0": spec.B0,
            "h": spec.h,
            "theta_bar": spec.theta_bar,
        }
        if spec.w is None:
            d.update(reflectance=tex, albedo_mode="normal")
        else:
            d.update(reflectance=spec.w, albedo_mode="w")
        return d
    raise ValueError(
        f"bsdf must be a LambertBSDF, OrenNayarBSDF or HapkeBSDF spec, got {type(spec).__name__}"
    )
