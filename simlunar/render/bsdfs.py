"""Mitsuba ``load_dict`` entries for simlunar's BSDF specs.

:func:`bsdf_dict` turns a spec of :data:`simlunar.render.materials.BSDFS` into its
``load_dict`` entry (the spec's own ``mitsuba_dict``: the built-in ``diffuse`` or one of
simlunar's plugins). The plugins live in :mod:`simlunar.render.plugins` (one module each, with
its parameter table) and are registered by :func:`simlunar.render.backend.init` once the
variant is set. Importing this module never imports Mitsuba.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from simlunar.render.materials import BSDFS
from simlunar.render.plugins.hapke import HAPKE_TABLE_SIZE

__all__ = ["HAPKE_TABLE_SIZE", "bsdf_dict"]


def _texture(reflectance: Any) -> Any:
    if isinstance(reflectance, (int, float, np.floating, np.integer)):
        v = float(reflectance)
        if not (math.isfinite(v) and 0.0 <= v <= 1.0):
            raise ValueError(f"reflectance must be in [0, 1], got {reflectance!r}")
        return v
    return reflectance


def bsdf_dict(spec, reflectance: Any = 0.5) -> dict:
    """Mitsuba ``load_dict`` entry for a BSDF spec.

    Parameters
    ----------
    spec : a spec of :data:`simlunar.render.materials.BSDFS`
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
    if not any(isinstance(spec, e.target) for e in BSDFS.values()):
        specs = ", ".join(e.target.__name__ for e in BSDFS.values())
        raise ValueError(f"bsdf must be a {specs} spec, got {type(spec).__name__}")
    return spec.mitsuba_dict(tex)
