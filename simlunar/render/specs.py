"""All rendering specs in one place (NumPy only, importable without Mitsuba).

Light specs come from :mod:`simlunar.render.lights`, BSDF specs from
:mod:`simlunar.render.materials`; this module only gathers them (CONTRIBUTING.md).
"""

from __future__ import annotations

from simlunar.render.lights import (
    LIGHTS,
    SUN_ANGULAR_DIAMETER,
    AmbientLight,
    CameraLight,
    ProjectorLight,
    SunLight,
    make_light,
)
from simlunar.render.materials import BSDFS, HapkeBSDF, LambertBSDF, OrenNayarBSDF, make_bsdf

__all__ = [
    "BSDFS",
    "LIGHTS",
    "SUN_ANGULAR_DIAMETER",
    "AmbientLight",
    "CameraLight",
    "HapkeBSDF",
    "LambertBSDF",
    "OrenNayarBSDF",
    "ProjectorLight",
    "SunLight",
    "make_bsdf",
    "make_light",
]
