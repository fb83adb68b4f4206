"""Validated terrain parameters (SI units) and their construction from a plain dict.

The library's own route from a preset mapping to :class:`TerrainParams`; the pipeline reads
preset files through its typed models (:mod:`simlunar.config.schema`'s
``TerrainPresetCfg``) and gives the same parameters.

YAML presets use unit suffixes (``spacing_m``, ``d_min_m``, ``diffusivity_m2_per_myr``);
:func:`params_from_dict` converts them to these fields once. Every error names the field
(``craters.d_max_m`` ...).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import ClassVar

import numpy as np

import simlunar.terrain.sfd as sfd

__all__ = [
    "AlbedoParams",
    "BedParams",
    "CraterParams",
    "FractalParams",
    "ParamError",
    "RockParams",
    "TerrainParams",
]


class ParamError(ValueError):
    """An invalid terrain parameter: ``key`` is its YAML path (``fractal.rms_m``).

    ``str()`` reads ``"<key> <problem>"``; callers that report key paths themselves use
    ``key`` and ``problem`` separately. (Experiment YAMLs validate presets and overrides with the
    pipeline's models, :mod:`simlunar.config.terrain`; a test keeps both routes equal.)
    """

    def __init__(self, key: str, problem: str):
        super().__init__(f"{key} {problem}")
        self.key = key
        self.problem = problem


def _num(v, name, *, lo=None, lo_open=False, hi=None, hi_open=False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise ParamError(name, f"must be a number, got {v!r}")
    v = float(v)
    bad = not np.isfinite(v)
    if lo is not None:
        bad |= v <= lo if lo_open else v < lo
    if hi is not None:
        bad |= v >= hi if hi_open else v > hi
    if bad:
        lo_s = "" if lo is None else f"{'(' if lo_open else '['}{lo}"
        hi_s = "" if hi is None else f"{hi}{')' if hi_open else ']'}"
        raise ParamError(
            name, f"must be a finite number in {lo_s or '(-inf'}, {hi_s or 'inf)'}, got {v!r}"
        )
    return v


def _check_diameters(what: str, d_min, d_max) -> None:
    """A population's diameter range: positive numbers (m), ``d_max`` above ``d_min``."""
    _num(d_min, f"{what}.d_min_m", lo=0.0, lo_open=True)
    _num(d_max, f"{what}.d_max_m", lo=0.0, lo_open=True)
    if d_max <= d_min:
        raise ValueError(
            f"{what} diameter range is empty: {what}.d_max_m ({d_max}) must exceed "
            f"{what}.d_min_m ({d_min})"
        )


@dataclass(frozen=True)
class FractalParams:
    """fBm base: Hurst exponent in (0, 1), RMS height (m), periodic, roll-off wavelength (m)."""

    hurst: float = 0.8
    rms: float = 0.2
    periodic: bool = False
    rolloff: float | None = None

    def __post_init__(self):
        _num(self.hurst, "fractal.hurst", lo=0.0, lo_open=True, hi=1.0, hi_open=True)
        _num(self.rms, "fractal.rms_m", lo=0.0)
        if self.rolloff is not None:
            _num(self.rolloff, "fractal.rolloff_m", lo=0.0, lo_open=True)


@dataclass(frozen=True)
class BedParams:
    """Low-frequency undulating bed: RMS amplitude (m; 0 = none) and wavelength (m)."""

    amplitude: float = 0.0
    wavelength: float = 1.0

    def __post_init__(self):
        _num(self.amplitude, "bed.amplitude_m", lo=0.0)
        _num(self.wavelength, "bed.wavelength_m", lo=0.0, lo_open=True)


@dataclass(frozen=True)
class _Population:
    """A size-frequency population (craters, rocks): on/off, its cumulative law
    (:func:`simlunar.terrain.sfd.get_law`; ``coefficient`` and ``exponent`` of a power law) and
    the diameter range (m) it is drawn over.

    Checks, in order: the diameter range, the subclass's own fields (:meth:`_check_own`), then
    the law (an unknown law or bad power-law parameters fail last).
    """

    enabled: bool = True
    law: str = ""
    d_min: float = 1.0
    d_max: float = 30.0
    coefficient: float | None = None
    exponent: float | None = None

    #: the population's YAML section, in messages (``craters.d_min_m``) and for its law
    section: ClassVar[str] = ""

    def __post_init__(self):
        _check_diameters(self.section, self.d_min, self.d_max)
        self._check_own()
        self.law_fn()

    def _check_own(self):
        """Check the subclass's own fields (``ParamError`` naming the key)."""

    def law_fn(self):
        """The population's cumulative size-frequency law (:func:`sfd.get_law`)."""
        return sfd.get_law(
            self.section, self.law, coefficient=self.coefficient, exponent=self.exponent
        )


@dataclass(frozen=True)
class CraterParams(_Population):
    """Crater population: cumulative law, diameter range (m), diffusion degradation."""

    law: str = "trask"
    diffusivity: float = 5.5  # m^2/Myr, Fassett & Thomson 2014
    max_age_myr: float = 20.0

    section: ClassVar[str] = "craters"

    def _check_own(self):
        _num(self.diffusivity, "craters.diffusivity_m2_per_myr", lo=0.0)
        _num(self.max_age_myr, "craters.max_age_myr", lo=0.0)


@dataclass(frozen=True)
class RockParams(_Population):
    """Rock population: cumulative law, diameter range (m), clustering, albedo contrast."""

    law: str = "intercrater"
    d_min: float = 0.3
    d_max: float = 3.0
    cluster_fraction: float = 0.5
    cluster_radius: float = 3.0
    mean_per_cluster: float = 8.0
    albedo_contrast: float = 0.1

    section: ClassVar[str] = "rocks"

    def _check_own(self):
        _num(self.cluster_fraction, "rocks.cluster_fraction", lo=0.0, hi=1.0)
        _num(self.cluster_radius, "rocks.cluster_radius_m", lo=0.0, lo_open=True)
        _num(self.mean_per_cluster, "rocks.mean_per_cluster", lo=1.0)
        _num(self.albedo_contrast, "rocks.albedo_contrast", lo=-0.9, hi=5.0)


@dataclass(frozen=True)
class AlbedoParams:
    """Albedo: mean, relative low-frequency variation, relative per-cell noise, ejecta brightening."""

    mean: float = 0.12
    variation: float = 0.08
    noise: float = 0.02
    ejecta_brightening: float = 0.25
    uniform: bool = False

    def __post_init__(self):
        _num(self.mean, "albedo.mean", lo=0.0, lo_open=True, hi=1.0)
        _num(self.variation, "albedo.variation", lo=0.0, hi=1.0)
        _num(self.noise, "albedo.noise", lo=0.0, hi=1.0)
        _num(self.ejecta_brightening, "albedo.ejecta_brightening", lo=0.0, hi=5.0)


@dataclass(frozen=True)
class TerrainParams:
    """Everything :func:`simlunar.terrain.generate` needs (SI units)."""

    rows: int = 256
    cols: int = 256
    spacing: float = 0.2
    origin: tuple[float, float] = (0.0, 0.0)
    fractal: FractalParams = field(default_factory=FractalParams)
    bed: BedParams = field(default_factory=BedParams)
    craters: CraterParams = field(default_factory=CraterParams)
    rocks: RockParams = field(default_factory=RockParams)
    albedo: AlbedoParams = field(default_factory=AlbedoParams)
    name: str = "custom"
    description: str = ""

    def __post_init__(self):
        for key in ("rows", "cols"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 16:
                raise ParamError(f"grid.{key}", f"must be an integer >= 16, got {v!r}")
        _num(self.spacing, "grid.spacing_m", lo=0.0, lo_open=True)
        if len(self.origin) != 2:
            raise ValueError(f"grid.origin_m must be [x, y], got {self.origin!r}")
        object.__setattr__(
            self,
            "origin",
            (_num(self.origin[0], "grid.origin_m"), _num(self.origin[1], "grid.origin_m")),
        )

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax) of the grid in metres."""
        x0, y0 = self.origin
        return (x0, x0 + self.cols * self.spacing, y0 - self.rows * self.spacing, y0)

    def scaled(self, scale: float) -> TerrainParams:
        """Same spacing and statistics on a grid ``scale`` times as long on each side (>= 16)."""
        s = _num(scale, "scale", lo=0.0, lo_open=True, hi=1.0)
        if s == 1.0:
            return self
        return replace(self, rows=max(16, round(self.rows * s)), cols=max(16, round(self.cols * s)))
