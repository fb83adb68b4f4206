"""BSDF specifications and the BSDF registry (NumPy only, importable without Mitsuba).

``BSDFS`` names every BSDF once: ``name -> Entry(spec class, spec class)`` (the frozen spec
dataclass is its own options class), with ``meta["plugin"]`` the module of its Mitsuba plugin
(registered by :func:`simlunar.render.backend.init`; None for Mitsuba's built-in ``diffuse``)
and ``meta["label"]`` its display name. Every spec has ``mitsuba_dict(reflectance)``, its
``load_dict`` entry (:func:`simlunar.render.bsdfs.bsdf_dict`); the YAML models of the specs
without a hand-written one are derived from their fields (:mod:`simlunar.config.render`).
A new BSDF is its module in :mod:`simlunar.render.plugins` (spec + plugin), its NumPy
reference in :mod:`simlunar.render.reference` and one ``BSDFS.register`` line here
(CONTRIBUTING.md, "Adding a BSDF").

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
- ``LunarLambertBSDF`` and ``LROCEmpiricalBSDF``: the grid is the normal albedo (``pi f`` at
  ``i = e = g = 0``), as for Hapke.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from simlunar.registry import Registry
from simlunar.render.mesh import grid_texture
from simlunar.render.plugins.lroc_empirical import LROCEmpiricalBSDF
from simlunar.render.plugins.lunar_lambert import LunarLambertBSDF
from simlunar.render.reference import LUNAR_HAPKE

__all__ = [
    "BSDFS",
    "HapkeBSDF",
    "LambertBSDF",
    "OrenNayarBSDF",
    "check_sigma_map",
    "make_bsdf",
    "sigma_map_from_energy",
]


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

    def mitsuba_dict(self, reflectance: Any) -> dict:
        return {"type": "diffuse", "reflectance": reflectance}


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
    sigma_map : (rows, cols) float array or None
        Spatially varying roughness (radians, each in ``[0, pi/2)``), one value per terrain
        cell, attached like the albedo grid (texel (r, c) at vertex (r, c), nearest filter:
        :mod:`simlunar.render.mesh`). When given it replaces ``sigma`` at render time
        (``sigma`` stays the nominal value). ``None`` (default) renders the scalar ``sigma``
        through the original constant-folded kernel. Stored as a read-only float64 copy;
        specs compare equal when ``sigma``, ``model`` and the map's values are equal.
    """

    sigma: float = 0.0
    model: str = "full"
    sigma_map: np.ndarray | None = field(default=None, compare=False, repr=False)
    name = "oren_nayar"

    def __post_init__(self) -> None:
        s = _finite("sigma", self.sigma)
        if not (0.0 <= s < math.pi / 2):
            raise ValueError(f"sigma must be in [0, pi/2) radians, got {self.sigma!r}")
        if self.model not in ("full", "qualitative"):
            raise ValueError(f"model must be one of full, qualitative; got {self.model!r}")
        object.__setattr__(self, "sigma", s)
        if self.sigma_map is not None:
            m = check_sigma_map(self.sigma_map).copy()
            m.flags.writeable = False
            object.__setattr__(self, "sigma_map", m)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, OrenNayarBSDF):
            return NotImplemented
        a, b = self.sigma_map, other.sigma_map
        same_map = (a is None and b is None) or (
            a is not None and b is not None and a.shape == b.shape and np.array_equal(a, b)
        )
        return self.sigma == other.sigma and self.model == other.model and same_map

    def mitsuba_dict(self, reflectance: Any) -> dict:
        """``oren_nayar`` plugin entry; a ``sigma_map`` becomes a nearest ``bitmap`` texture
        addressed as a grid albedo (:func:`simlunar.render.mesh.grid_texture`)."""
        sigma: Any = self.sigma if self.sigma_map is None else grid_texture(self.sigma_map)
        return {
            "type": "oren_nayar",
            "reflectance": reflectance,
            "sigma": sigma,
            "model": self.model,
        }


def check_sigma_map(sigma_map: Any, name: str = "sigma_map") -> np.ndarray:
    """Validate a per-cell Oren-Nayar roughness grid.

    Parameters
    ----------
    sigma_map : (rows, cols) array_like
        Facet slope standard deviations in radians.
    name : str
        Field name used in error messages.

    Returns
    -------
    (rows, cols) float64

    Raises
    ------
    ValueError
        Not 2-D, empty, non-finite, or a value outside ``[0, pi/2)`` (the message names the
        field, the offending range and the first offending cell).
    """
    try:
        m = np.asarray(sigma_map, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a 2-D array of numbers") from None
    if m.ndim != 2 or m.size == 0:
        raise ValueError(f"{name} must be a non-empty 2-D (rows, cols) array, got shape {m.shape}")
    bad = ~np.isfinite(m) | (m < 0.0) | (m >= math.pi / 2)
    if bad.any():
        r, c = (int(i) for i in np.argwhere(bad)[0])
        raise ValueError(
            f"{name} values must be finite and in [0, pi/2) radians; got range "
            f"[{np.nanmin(m):.6g}, {np.nanmax(m):.6g}] (first bad cell ({r}, {c}) = {float(m[r, c])!r})"
        )
    return m


def sigma_map_from_energy(
    energy: np.ndarray,
    *,
    sigma_min: float,
    sigma_max: float,
    threshold: float | None = None,
    percentile: float = 99.0,
) -> np.ndarray:
    """Per-cell Oren-Nayar roughness from a frequency (wavelet energy) map (paper Fig. 4).

    The energy is normalised robustly, ``e = clip(energy / P, 0, 1)`` with ``P`` its
    ``percentile``-th percentile (so a few crater rims do not flatten the rest), and mapped
    linearly, ``sigma = sigma_min + (sigma_max - sigma_min) * e``: the more high-frequency
    detail a cell had, the rougher the downsampled surface is shaded, standing in for the
    relief the sparse mesh lost. Cells with ``e >= threshold`` are the major features: the
    wavelet planner concentrates its samples there, so the reconstructed mesh already carries
    their relief metrically and they get ``sigma_min`` (no roughness on top of real geometry).

    Parameters
    ----------
    energy : (rows, cols) float
        Non-negative frequency map, e.g. ``simlunar.features.feature_map("wavelet", image)``
        of the nadir guide image (pixel (r, c) = terrain cell (r, c)).
    sigma_min, sigma_max : float
        Roughness range in radians, ``0 <= sigma_min <= sigma_max < pi/2``.
    threshold : float in (0, 1] or None
        Normalised energy at and above which the geometry is kept metric; ``None`` disables.
    percentile : float in (0, 100]
        Normalisation percentile of the energy.

    Returns
    -------
    (rows, cols) float64
        Roughness in radians, within ``[sigma_min, sigma_max]``. An all-zero energy map gives
        ``sigma_min`` everywhere.

    Raises
    ------
    ValueError
        Bad range, threshold, percentile, or an energy map that is not 2-D, finite and >= 0.
    """
    e = np.asarray(energy, dtype=np.float64)
    if e.ndim != 2 or e.size == 0:
        raise ValueError(f"energy must be a non-empty 2-D array, got shape {e.shape}")
    if not np.isfinite(e).all() or (e < 0).any():
        raise ValueError("energy must be finite and >= 0")
    lo, hi = _finite("sigma_min", sigma_min), _finite("sigma_max", sigma_max)
    if not (0.0 <= lo <= hi < math.pi / 2):
        raise ValueError(
            f"sigma_min, sigma_max must satisfy 0 <= sigma_min <= sigma_max < pi/2 radians, "
            f"got {sigma_min!r}, {sigma_max!r}"
        )
    if threshold is not None and not (0.0 < _finite("threshold", threshold) <= 1.0):
        raise ValueError(f"threshold must be in (0, 1] or None, got {threshold!r}")
    if not (0.0 < _finite("percentile", percentile) <= 100.0):
        raise ValueError(f"percentile must be in (0, 100], got {percentile!r}")
    ref = float(np.percentile(e, percentile))
    if ref <= 0.0:
        ref = float(e.max())
    norm = np.clip(e / ref, 0.0, 1.0) if ref > 0.0 else np.zeros_like(e)
    sigma = lo + (hi - lo) * norm
    if threshold is not None:
        sigma[norm >= threshold] = lo
    return sigma


@dataclass(frozen=True)
class HapkeBSDF:
    """Hapke reflectance (shadow-hiding and coherent-backscatter opposition surges, double
    Henyey-Greenstein phase function, macroscopic roughness; see
    :func:`simlunar.render.reference.hapke`).

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
        Shadow-hiding opposition surge amplitude ``B_S0``, >= 0 (0 disables the surge).
    h : float
        Shadow-hiding opposition surge width ``h_S``, > 0.
    theta_bar : float
        Mean macroscopic slope in radians, [0, pi/2).
    B_C0 : float
        Coherent-backscatter opposition surge amplitude, >= 0 (0, the default, disables it).
    h_C : float
        Coherent-backscatter opposition surge width, > 0 (read only when ``B_C0 > 0``).
    """

    w: float | None = None
    b: float = LUNAR_HAPKE.b
    c: float = LUNAR_HAPKE.c
    B0: float = LUNAR_HAPKE.B0
    h: float = LUNAR_HAPKE.h
    theta_bar: float = LUNAR_HAPKE.theta_bar
    B_C0: float = LUNAR_HAPKE.B_C0
    h_C: float = LUNAR_HAPKE.h_C
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
            "B_C0": lambda v: v >= 0.0,
            "h_C": lambda v: v > 0.0,
        }
        ranges = {
            "b": "[0, 1)",
            "c": "[-1, 1]",
            "B0": ">= 0",
            "h": "> 0",
            "theta_bar": "[0, pi/2) radians",
            "B_C0": ">= 0",
            "h_C": "> 0",
        }
        for key, ok in checks.items():
            v = _finite(key, getattr(self, key))
            if not ok(v):
                raise ValueError(f"{key} must be {ranges[key]}, got {getattr(self, key)!r}")
            object.__setattr__(self, key, v)

    def mitsuba_dict(self, reflectance: Any) -> dict:
        """``hapke`` plugin entry: ``reflectance`` is the normal albedo unless ``w`` is set."""
        d = {"type": "hapke", "b": self.b, "c": self.c, "B0": self.B0, "h": self.h}
        d["theta_bar"] = self.theta_bar
        if self.B_C0 != 0.0:  # the plugin's default B_C0 = 0 leaves the surge out
            d.update(B_C0=self.B_C0, h_C=self.h_C)
        if self.w is None:
            d.update(reflectance=reflectance, albedo_mode="normal")
        else:
            d.update(reflectance=self.w, albedo_mode="w")
        return d


#: BSDF name -> Entry(spec class, spec class); meta: plugin (module name or None), label
BSDFS = Registry("BSDF")
BSDFS.register("lambert", LambertBSDF, LambertBSDF, label="Lambert", plugin=None)
BSDFS.register(
    "oren_nayar",
    OrenNayarBSDF,
    OrenNayarBSDF,
    label="Oren-Nayar",
    plugin="simlunar.render.plugins.oren_nayar",
)
BSDFS.register("hapke", HapkeBSDF, HapkeBSDF, label="Hapke", plugin="simlunar.render.plugins.hapke")
BSDFS.register(
    "lunar_lambert",
    LunarLambertBSDF,
    LunarLambertBSDF,
    label="Lunar-Lambert",
    plugin="simlunar.render.plugins.lunar_lambert",
)
BSDFS.register(
    "lroc_empirical",
    LROCEmpiricalBSDF,
    LROCEmpiricalBSDF,
    label="LROC Empirical",
    plugin="simlunar.render.plugins.lroc_empirical",
)


def make_bsdf(name: str, **kw: Any):
    """Build a BSDF spec by registry name.

    Parameters
    ----------
    name : a name of :data:`BSDFS` (lambert, oren_nayar, hapke, ...)
    **kw
        Fields of the spec (e.g. ``sigma=0.3`` for Oren-Nayar).

    Raises
    ------
    ValueError
        Unknown name (lists the valid ones), unknown keyword (lists the valid fields), or a
        parameter out of range (names the field).
    """
    cls = BSDFS[name].target  # an unknown name lists the valid ones
    valid = [f.name for f in fields(cls)]
    bad = sorted(set(kw) - set(valid))
    if bad:
        raise ValueError(
            f"unknown parameter(s) {', '.join(bad)} for BSDF {name!r}; "
            f"valid: {', '.join(valid) or '(none)'}"
        )
    return cls(**kw)
