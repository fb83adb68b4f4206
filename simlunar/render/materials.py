"""BSDF specifications (NumPy only, importable without Mitsuba).

A spec says *which* reflectance model and with which angular parameters; it does not hold an
albedo. The albedo comes from the terrain's albedo grid (``Terrain.albedo``, normal albedo per
cell) and is attached at scene build time as a Mitsuba texture by
:func:`simlunar.render.bsdfs.bsdf_dict`:

- ``LambertBSDF``: the grid is the diffuse reflectance (built-in Mitsuba ``diffuse``).
- ``OrenNayarBSDF``: the grid is the facet albedo ``rho`` of Oren & Nayar (1994).
- ``HapkeBSDF``: with ``w=None`` (default) each point gets the single-scattering albedo whose
  Hapke *normal albedo* equals the grid value (:func:`simlunar.render.reference.hapke_w_from_normal_albedo`),
  so a Hapke and a Lambert terrain built from the same grid look equally bright when seen and
  lit from straight above; with a number ``w`` the whole surface uses that single-scattering
  albedo and the grid is ignored.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

from simlunar.render.reference import LUNAR_HAPKE

__all__ = ["BSDFS", "HapkeBSDF", "LambertBSDF", "OrenNayarBSDF", "make_bsdf"]


def _finite(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return v


@dataclass(frozen=True)
class LambertBSDF:
    """Lambertian reflectance ``albedo / pi`` (Mitsuba's built-in ``diffuse``)."""

    name = "lambert"


@dataclass(frozen=True)
class OrenNayarBSDF:
    """Oren-Nayar rough diffuse reflectance.

    Parameters
    ----------
    sigma : float
        Facet slope standard deviation in radians, ``0 <= sigma < pi/2`` (Oren & Nayar 1994;
        Mitsuba 0.6's roughness ``alpha`` corresponds to ``sigma = alpha / sqrt(2)``).
        ``sigma = 0`` is Lambert.
    model : {"full", "qualitative"}
        The full 1994 model (C1..C3 terms and the inter-reflection term) or the simplified
        A/B form.
    """

    sigma: float = 0.0
    model: str = "full"
    name = "oren_nayar"

    def __post_init__(self) -> None:
        s = _finite("sigma", self.sigma)
        if not (0.0 <= s < math.pi / 2):
            raise ValueError(f"sigma must be in [0, pi/2) radians, got {self.sigma!r}")
        if self.model not in ("full", "qualitative"):
            raise ValueError(f"model must be one of full, qualitative; got {self.model!r}")
        object.__setattr__(self, "sigma", s)


@dataclass(frozen=True)
class HapkeBSDF:
    """Hapke reflectance (shadow-hiding opposition surge, double Henyey-Greenstein phase
    function, macroscopic roughness; see :func:`simlunar.render.reference.hapke`).

    Defaults are the lunar values of :data:`simlunar.render.reference.LUNAR_HAPKE` (see there
    for sources and which numbers are unverified).

    Parameters
    ----------
    w : float or None
        Single-scattering albedo in [0, 1]; ``None`` derives it per point from the terrain
        albedo grid (normal-albedo match).
    b : float
        Henyey-Greenstein lobe width in [0, 1).
    c : float
        Backscatter weight parameter in [-1, 1] (backscatter lobe (1 + c)/2).
    B0 : float
        Opposition surge amplitude, >= 0 (0 disables the surge).
    h : float
        Opposition surge width, > 0.
    theta_bar : float
        Mean macroscopic slope in radians, [0, pi/2).
    """

    w: float | None = None
    b: float = LUNAR_HAPKE.b
    c: float = LUNAR_HAPKE.c
    B0: float = LUNAR_HAPKE.B0
    h: float = LUNAR_HAPKE.h
    theta_bar: float = LUNAR_HAPKE.theta_bar
    name = "hapke"

    def __post_init__(self) -> None:
        if self.w is not None:
            w = _finite("w", self.w)
            if not 0.0 <= w <= 1.0:
                raise ValueError(f"w must be in [0, 1], got {self.w!r}")
            object.__setattr__(self, "w", w)
        checks = {
            "b": lambda v: 0.0 <= v < 1.0,
            "c": lambda v: -1.0 <= v <= 1.0,
            "B0": lambda v: v >= 0.0,
            "h": lambda v: v > 0.0,
            "theta_bar": lambda v: 0.0 <= v < math.pi / 2,
        }
        ranges = {
            "b": "[0, 1)",
            "c": "[-1, 1]",
            "B0": ">= 0",
            "h": "> 0",
            "theta_bar": "[0, pi/2) radians",
        }
        for key, ok in checks.items():
            v = _finite(key, getattr(self, key))
            if not ok(v):
                raise ValueError(f"{key} must be {ranges[key]}, got {getattr(self, key)!r}")
            object.__setattr__(self, key, v)


BSDFSpec = LambertBSDF | OrenNayarBSDF | HapkeBSDF

#: name -> spec class
BSDFS: dict[str, type] = {
    "lambert": LambertBSDF,
    "oren_nayar": OrenNayarBSDF,
    "hapke": HapkeBSDF,
}


def make_bsdf(name: str, **kw: Any) -> LambertBSDF | OrenNayarBSDF | HapkeBSDF:
    """Build a BSDF spec by registry name.

    Parameters
    ----------
    name : {"lambert", "oren_nayar", "hapke"}
    **kw
        Fields of the spec (e.g. ``sigma=0.3`` for Oren-Nayar).

    Raises
    ------
    ValueError
        Unknown name (lists the valid ones), unknown keyword (lists the valid fields), or a
        parameter out of range (names the field).
    """
    try:
        cls = BSDFS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown BSDF {name!r}; valid: {', '.join(BSDFS)}") from None
    valid = [f.name for f in fields(cls)]
    bad = sorted(set(kw) - set(valid))
    if bad:
        raise ValueError(
            f"unknown parameter(s) {', '.join(bad)} for BSDF {name!r}; "
            f"valid: {', '.join(valid) or '(none)'}"
        )
    return cls(**kw)
