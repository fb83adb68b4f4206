"""Terrain sections of the schema: presets (``scenes/*.yaml``), overrides and an experiment's ``terrain``."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Annotated, ClassVar

import yaml
from pydantic import Field, ValidationError, model_validator

from simlunar.config.fields import Metres, _Model, _partial, _SetKeysModel
from simlunar.config.messages import format_validation_error
from simlunar.config.yamlio import load_yaml
from simlunar.errors import ConfigError
from simlunar.registry import FileOption, did_you_mean, did_you_mean_file
from simlunar.terrain.sfd import get_law

__all__ = [
    "PRESET_SECTIONS",
    "SCENES",
    "AlbedoCfg",
    "BedCfg",
    "CratersCfg",
    "FractalCfg",
    "GridCfg",
    "PresetError",
    "RocksCfg",
    "TerrainCfg",
    "TerrainOverridesCfg",
    "TerrainPresetCfg",
    "merged_preset",
    "preset_data",
    "preset_names",
    "preset_path",
]


# --------------------------------------------------------------------------- terrain
# The terrain preset files (scenes/aerial_1.yaml, ...) and an experiment's terrain.overrides use
# these models; :mod:`simlunar.config.translate` turns them into
# :class:`simlunar.terrain.params.TerrainParams`. Defaults are the terrain package's.
class _PopulationCfg(_Model):
    """Shared check of a crater or rock population (each declares the fields ``law``,
    ``d_min_m``, ``d_max_m``, ``coefficient`` and ``exponent``, with its own defaults):
    a non-empty diameter range and a size-frequency law the terrain package knows."""

    #: the population kind of :func:`simlunar.terrain.sfd.get_law`
    _kind: ClassVar[str]

    @model_validator(mode="after")
    def _range_and_law(self):
        if self.d_max_m <= self.d_min_m:
            raise ValueError(
                f"d_max_m: the diameter range is empty ({self.d_max_m} <= d_min_m {self.d_min_m})"
            )
        get_law(self._kind, self.law, coefficient=self.coefficient, exponent=self.exponent)
        return self


class GridCfg(_Model):
    """The height grid: rows x cols cells of ``spacing_m``; ``origin_m`` = top-left (x, y)."""

    rows: int = Field(256, ge=16)
    cols: int = Field(256, ge=16)
    spacing_m: Metres = Field(0.2, gt=0, description="cell size (m)")
    origin_m: tuple[float, float] = Field((0.0, 0.0), description="top-left corner (x, y) (m)")


class FractalCfg(_Model):
    """fBm base surface."""

    hurst: float = Field(0.8, gt=0, lt=1, description="Hurst exponent")
    rms_m: Metres = Field(0.2, ge=0, description="RMS height (m)")
    periodic: bool = False
    rolloff_m: Metres | None = Field(None, gt=0, description="roll-off wavelength (m); null = none")


class BedCfg(_Model):
    """Low-frequency undulating bed."""

    amplitude_m: Metres = Field(0.0, ge=0, description="RMS amplitude (m); 0 = none")
    wavelength_m: Metres = Field(1.0, gt=0)


class CratersCfg(_PopulationCfg):
    """Crater population: cumulative size-frequency law, diameter range, degradation."""

    enabled: bool = True
    law: str = Field("trask", description="trask, viper or power (then coefficient, exponent)")
    d_min_m: Metres = Field(1.0, gt=0)
    d_max_m: Metres = Field(30.0, gt=0)
    coefficient: float | None = Field(None, gt=0, description="power law: N(>D) = c D^-e per m^2")
    exponent: float | None = Field(None, gt=0)
    diffusivity_m2_per_myr: float = Field(5.5, ge=0, description="topographic diffusion")
    max_age_myr: float = Field(20.0, ge=0)

    _kind: ClassVar[str] = "craters"  # of the law (simlunar.terrain.sfd.get_law)


class RocksCfg(_PopulationCfg):
    """Rock population: cumulative law, diameter range, clustering, albedo contrast."""

    enabled: bool = True
    law: str = Field(
        "intercrater",
        description="a rock law name, power (then coefficient, exponent) or golombek (then "
        "coefficient = k, the rock area fraction: F(>D) = k exp(-q(k) D))",
    )
    d_min_m: Metres = Field(0.3, gt=0)
    d_max_m: Metres = Field(3.0, gt=0)
    coefficient: float | None = Field(None, gt=0)
    exponent: float | None = Field(None, gt=0)
    cluster_fraction: float = Field(0.5, ge=0, le=1)
    cluster_radius_m: Metres = Field(3.0, gt=0)
    mean_per_cluster: float = Field(8.0, ge=1)
    albedo_contrast: float = Field(0.1, ge=-0.9, le=5)

    _kind: ClassVar[str] = "rocks"  # of the law (simlunar.terrain.sfd.get_law)


class AlbedoCfg(_Model):
    """Albedo: mean, relative low-frequency variation and per-cell noise, ejecta brightening."""

    mean: float = Field(0.12, gt=0, le=1)
    variation: float = Field(0.08, ge=0, le=1)
    noise: float = Field(0.02, ge=0, le=1)
    ejecta_brightening: float = Field(0.25, ge=0, le=5)
    uniform: bool = False


class TerrainPresetCfg(_Model):
    """A terrain preset file (``scenes/<name>.yaml``): the generator's parameters."""

    name: str = "custom"
    description: str = ""
    sources: list[str] = Field(default_factory=list, description="provenance of the numbers")
    grid: GridCfg = Field(default_factory=GridCfg)
    fractal: FractalCfg = Field(default_factory=FractalCfg)
    bed: BedCfg = Field(default_factory=BedCfg)
    craters: CratersCfg = Field(default_factory=CratersCfg)
    rocks: RocksCfg = Field(default_factory=RocksCfg)
    albedo: AlbedoCfg = Field(default_factory=AlbedoCfg)


#: the preset sections an experiment may override
PRESET_SECTIONS = ("grid", "fractal", "bed", "craters", "rocks", "albedo")


class TerrainOverridesCfg(_SetKeysModel):
    """Preset parameters to change: ``{section: {key: value}}``, deep-merged into the preset
    before its validation (e.g. ``{fractal: {rms_m: 0.05}}``). Each section takes the keys of
    the terrain preset's section of the same name (below), all optional; unset keys keep the
    preset's value."""

    grid: _partial(GridCfg) | None = None  # type: ignore[valid-type]
    fractal: _partial(FractalCfg) | None = None  # type: ignore[valid-type]
    bed: _partial(BedCfg) | None = None  # type: ignore[valid-type]
    craters: _partial(CratersCfg) | None = None  # type: ignore[valid-type]
    rocks: _partial(RocksCfg) | None = None  # type: ignore[valid-type]
    albedo: _partial(AlbedoCfg) | None = None  # type: ignore[valid-type]

    def as_mapping(self) -> dict[str, dict]:
        """The set keys only: ``{section: {key: value}}`` (empty sections dropped)."""
        return {k: v for k, v in self.model_dump().items() if v}


class TerrainCfg(_Model):
    """Terrain: a named preset (``scenes/<name>.yaml``) or a DEM file."""

    preset: Annotated[str | None, FileOption("preset")] = Field(
        None, description="terrain preset name, e.g. aerial_1, moonyard"
    )
    scale: float = Field(1.0, gt=0, le=1, description="preset resolution scale (1/8 = small)")
    file: Annotated[Path | None, FileOption("dem")] = Field(
        None, description="DEM file (.npy, .tif, .exr); relative to the YAML"
    )
    spacing_m: Metres | None = Field(
        None, gt=0, description="DEM cell size (m), for a file without georeferencing"
    )
    albedo_file: Annotated[Path | None, FileOption("albedo")] = Field(
        None, description="albedo grid file (.npy, same shape as the DEM), for file"
    )
    albedo: float | None = Field(
        None, ge=0, le=1, description="replace the albedo by this uniform value (ablation)"
    )
    refine_m: Metres | None = Field(
        None,
        gt=0,
        description="with terrain.file: its heights resampled bilinearly to finer square cells "
        "of this size first (a 1-5 m DEM resolves no 15 cm rock; no detail is added)",
    )
    rocks: RocksCfg | None = Field(
        None,
        description="with terrain.file: rocks stamped on its surface, a preset's rocks section "
        "(e.g. {law: golombek, coefficient: 0.07, d_min_m: 0.1}); each terrain seed "
        "(seed_index) draws its own rocks on the same surface",
    )
    overrides: TerrainOverridesCfg = Field(
        default_factory=TerrainOverridesCfg,
        description="preset parameters to change, deep-merged into the preset before its "
        "validation: {section: {key: value}}, e.g. {fractal: {rms_m: 0.05}}; sections grid, "
        "fractal, bed, craters, rocks, albedo with the preset YAML's keys",
    )

    seed_index: int = Field(
        0,
        ge=0,
        lt=10000,
        description="terrain realisation of a preset: 0 = the experiment seed's terrain, "
        "i > 0 = its i-th independent child stream (set per unit by study.terrain_seeds)",
    )

    @model_validator(mode="after")
    def _one_source(self) -> TerrainCfg:
        if (self.preset is None) == (self.file is None):
            raise ValueError("give exactly one of preset or file")
        if self.albedo_file is not None and self.file is None:
            raise ValueError("albedo_file goes with a DEM file (give terrain.file)")
        if self.preset is None and self.overrides.model_dump():
            raise ValueError("overrides: overrides apply to a preset only (give terrain.preset)")
        if self.preset is not None:
            # the preset file, with the overrides merged in, must be valid (same models)
            try:
                merged_preset(self.preset, self.overrides)
            except PresetError as exc:
                if exc.key is not None:
                    raise ValueError(f"overrides.{exc.key}: {exc.problem}") from None
                raise ValueError(f"preset: {exc.problem}") from None
        if self.file is None and (self.rocks is not None or self.refine_m is not None):
            key = "rocks" if self.rocks is not None else "refine_m"
            raise ValueError(
                f"{key}: goes with a DEM file (terrain.file); a preset's rocks are "
                "overrides: {rocks: {...}} and its cells overrides: {grid: {spacing_m: ...}}"
            )
        if self.file is not None and self.seed_index != 0 and self.rocks is None:
            raise ValueError(
                "seed_index applies to a preset, or to a DEM file with rocks (a DEM file alone "
                "has one terrain)"
            )
        # every key set must change the result: a DEM file's keys on a preset (and the
        # preset's scale on a file) would be recorded in config.yaml yet change nothing
        if self.preset is not None and self.spacing_m is not None:
            raise ValueError(
                "spacing_m: the cell size of a DEM file (terrain.file) has no effect on a "
                "preset; change the preset's grid with overrides: {grid: {spacing_m: ...}}"
            )
        if self.file is not None and self.scale != 1.0:
            raise ValueError(
                "scale: shrinks a preset's grid and has no effect on a DEM file (terrain.file); "
                "resample the file instead"
            )
        return self


# --------------------------------------------------------------------------- preset files
# ``scenes/<name>.yaml`` read through the models above; an experiment's ``terrain.overrides``
# is deep-merged in before validation, so the rules are the same models' either way.
#: the folder of the shipped terrain presets (and the quickstart scene)
SCENES = Path(__file__).resolve().parents[2] / "scenes"


def preset_names() -> list[str]:
    """Names of the terrain presets shipped in ``scenes/`` (files with a ``grid`` section)."""
    out = []
    for p in sorted(SCENES.glob("*.yaml")):
        try:
            d = yaml.safe_load(p.read_text())
        except (OSError, yaml.YAMLError):
            continue
        if isinstance(d, dict) and "grid" in d and "craters" in d:
            out.append(p.stem)
    return out


class PresetError(ValueError):
    """An invalid preset or override: ``key`` is the key path inside the preset (or None when
    the preset itself, not an override, is at fault: unknown name, unreadable file)."""

    def __init__(self, key: str | None, problem: str):
        super().__init__(f"{key}: {problem}" if key else problem)
        self.key = key
        self.problem = problem


def preset_path(name: str | Path) -> Path:
    """The YAML file of a preset name (``aerial_1``) or path (``my/preset.yaml``)."""
    name = str(name)
    looks_like_path = name.endswith((".yaml", ".yml")) or "/" in name or "\\" in name
    path = Path(name) if looks_like_path else SCENES / f"{name}.yaml"
    if not path.is_file():
        if looks_like_path:
            raise PresetError(
                None, f"terrain preset file not found: {path}{did_you_mean_file(path)}"
            )
        valid = preset_names()
        raise PresetError(
            None,
            f"unknown terrain preset {name!r} (valid: {', '.join(valid)})"
            f"{did_you_mean(name, valid)}",
        )
    return path


@functools.lru_cache(maxsize=64)
def _read(path: Path, mtime_ns: int, size: int) -> dict:
    try:
        data = load_yaml(path)
    except ConfigError as exc:
        raise PresetError(None, str(exc)) from None
    if not isinstance(data, dict):
        raise PresetError(None, f"{path}: <root>: expected a mapping of keys")
    return data


def preset_data(name: str) -> dict:
    """The parsed YAML mapping of a preset (cached by path, modification time and size)."""
    path = preset_path(name)
    st = path.stat()
    return _read(path.resolve(), st.st_mtime_ns, st.st_size)


def _merge(data: dict, overrides: dict) -> dict:
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in data.items()}
    for sec, sub in overrides.items():
        merged = dict(out.get(sec) or {})
        merged.update(sub)
        out[sec] = merged
    return out


def merged_preset(name: str, overrides: TerrainOverridesCfg | None = None) -> TerrainPresetCfg:
    """A preset with ``overrides`` deep-merged in, validated.

    Raises
    ------
    PresetError
        ``key`` = the override's key path (``fractal.rms_m``) when an override makes the preset
        invalid; ``key`` None with a message naming the file when the preset itself is invalid.
    """
    data = preset_data(name)
    try:
        base = TerrainPresetCfg.model_validate(data)
    except ValidationError as exc:
        raise PresetError(
            None,
            f"{preset_path(name)}: {format_validation_error(exc, data, root=TerrainPresetCfg)}",
        ) from None
    ov = overrides.as_mapping() if overrides is not None else {}
    if not ov:
        return base
    merged = _merge(data, ov)
    try:
        return TerrainPresetCfg.model_validate(merged)
    except ValidationError as exc:
        line = format_validation_error(exc, merged, root=TerrainPresetCfg)
        key, _, problem = line.partition(": ")
        return_key = key if key.split(".")[0] in ov else None
        raise PresetError(return_key, problem if return_key else line) from None
