"""The experiment schema: typed pydantic v2 models of an experiment YAML.

Unknown keys are rejected everywhere (``extra="forbid"``). Keys carry their unit as a suffix
(``_deg``, ``_m``); values may be plain numbers in that unit or strings with an explicit unit
(``"0.5 rad"``, ``"20 cm"``), converted once here. Properties without the suffix
(``SunLightCfg.elevation``) give SI units / radians for the library. Loading, key-path error
messages and sweeps live in :mod:`simlunar.pipeline.config`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal, Union

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    ValidationInfo,
    field_validator,
    model_validator,
)

from simlunar.pipeline.units import log_spaced, parse_fraction, parse_quantity

Deg = Annotated[float, BeforeValidator(lambda v: parse_quantity(v, "deg"))]
Metres = Annotated[float, BeforeValidator(lambda v: parse_quantity(v, "m"))]
Density = Annotated[float, BeforeValidator(parse_fraction)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


def _tagged_union(default: str | None, *members: type[BaseModel]):
    """A union chosen by its ``kind`` key; a missing ``kind`` means ``default``."""
    tags = [m.model_fields["kind"].annotation.__args__[0] for m in members]

    def pick(v):
        if isinstance(v, dict):
            return v.get("kind", default)
        return getattr(v, "kind", default)

    union = Union[tuple(Annotated[m, Tag(t)] for m, t in zip(members, tags))]  # noqa: UP007
    return Annotated[
        union,
        Discriminator(
            pick,
            custom_error_type="bad_kind",
            custom_error_message=f"kind must be one of {', '.join(tags)}",
        ),
    ]


# --------------------------------------------------------------------------- terrain
class TerrainCfg(_Model):
    """Terrain: a named preset (``scenes/<name>.yaml``) or a DEM file."""

    preset: str | None = Field(None, description="terrain preset name, e.g. aerial_1, moonyard")
    scale: float = Field(1.0, gt=0, le=1, description="preset resolution scale (1/8 = small)")
    file: Path | None = Field(None, description="DEM file (.npy, .tif, .exr); relative to the YAML")
    spacing_m: Metres | None = Field(None, gt=0, description="DEM cell size (m), for file")
    albedo_file: Path | None = Field(None, description="optional albedo grid file")
    albedo: float | None = Field(
        None, ge=0, le=1, description="replace the albedo by this uniform value (ablation)"
    )
    overrides: dict[str, Any] = Field(
        default_factory=dict,
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

    @field_validator("overrides")
    @classmethod
    def _valid_overrides(cls, v: dict[str, Any], info: ValidationInfo) -> dict[str, Any]:
        # The terrain package validates (merge_overrides + params_from_dict), so the rules are
        # the presets' own. A ParamError names its key; it is reported as "<key>: <problem>",
        # which format_validation_error appends to this field's path
        # (terrain.overrides.fractal.rms_m: ...).
        if not v:
            return v
        from simlunar.terrain.params import ParamError
        from simlunar.terrain.presets import load_preset

        preset = info.data.get("preset")
        if preset is None:
            raise ValueError("overrides apply to a preset only (give terrain.preset)")
        try:
            load_preset(preset)
        except (ValueError, FileNotFoundError):
            return v  # a bad preset name is reported at terrain.preset
        try:
            load_preset(preset, overrides=v)
        except ParamError as exc:
            raise ValueError(f"{exc.key}: {exc.problem}" if exc.key else exc.problem) from None
        return v

    @model_validator(mode="after")
    def _one_source(self) -> TerrainCfg:
        if (self.preset is None) == (self.file is None):
            raise ValueError("give exactly one of preset or file")
        if self.file is not None and self.spacing_m is None:
            raise ValueError("a DEM file needs spacing_m")
        if self.file is not None and self.seed_index != 0:
            raise ValueError("seed_index applies to a preset only (a DEM file has one terrain)")
        return self


# --------------------------------------------------------------------------- render
class OrthoNadirCfg(_Model):
    """Orthographic nadir camera whose pixel (r, c) sees DEM cell (r, c) (aerial view)."""

    kind: Literal["orthographic_nadir"] = "orthographic_nadir"
    altitude_m: Metres = Field(50.0, gt=0, description="camera height above z = 0 (m)")


class PerspectiveCfg(_Model):
    """Pinhole camera at ``position_m`` looking at ``look_at_m``."""

    kind: Literal["perspective"]
    width: int = Field(gt=0)
    height: int = Field(gt=0)
    fov_deg: Deg = Field(gt=0, lt=180, description="horizontal field of view")
    position_m: tuple[float, float, float]
    look_at_m: tuple[float, float, float]


CameraCfg = _tagged_union("orthographic_nadir", OrthoNadirCfg, PerspectiveCfg)


class SunLightCfg(_Model):
    """A distant sun. Azimuth from +y (north) clockwise towards +x (east)."""

    kind: Literal["sun"] = "sun"
    elevation_deg: Deg = Field(30.0, ge=0, le=90)
    azimuth_deg: Deg = Field(135.0, ge=-360, le=360)
    irradiance: float = Field(1.0, gt=0, description="W/m^2 at normal incidence (relative)")
    angular_diameter_deg: Deg = Field(
        0.0, ge=0, lt=90, description="solar disk; 0.53 = the real sun (soft shadow edges)"
    )

    @property
    def elevation(self) -> float:
        return math.radians(self.elevation_deg)

    @property
    def azimuth(self) -> float:
        return math.radians(self.azimuth_deg)


class CameraLightCfg(_Model):
    """A point light at the camera's centre (no visible shadows)."""

    kind: Literal["camera"]
    intensity: float = Field(1.0, gt=0)


LightCfg = _tagged_union("sun", SunLightCfg, CameraLightCfg)


class LambertCfg(_Model):
    kind: Literal["lambert"]


class OrenNayarCfg(_Model):
    """Oren-Nayar (1994); ``sigma_deg`` is the slope standard deviation."""

    kind: Literal["oren_nayar"]
    sigma_deg: Deg = Field(20.0, ge=0, le=90)
    model: Literal["full", "qualitative"] = "full"

    @property
    def sigma(self) -> float:
        return math.radians(self.sigma_deg)


class HapkeCfg(_Model):
    """Hapke; unset parameters take the render package's lunar defaults."""

    kind: Literal["hapke"]
    w: float | None = Field(None, gt=0, le=1, description="single-scattering albedo")
    b: float | None = Field(None, ge=0, le=1)
    c: float | None = Field(None, ge=-1, le=1)
    B0: float | None = Field(None, ge=0)
    h: float | None = Field(None, gt=0)
    theta_bar_deg: Deg | None = Field(None, ge=0, le=60)


BsdfCfg = _tagged_union(None, LambertCfg, OrenNayarCfg, HapkeCfg)


class SensorCfg(_Model):
    """Camera sensor (:class:`simlunar.imaging.sensor.SensorModel`): shot noise, read noise, ADC."""

    full_well_e: float = Field(20000.0, gt=0, description="saturation capacity (electrons)")
    read_noise_e: float = Field(5.0, ge=0, description="read noise std (electrons)")
    bits: int = Field(12, ge=1, le=16, description="ADC resolution")
    exposure_e: float | None = Field(
        None,
        gt=0,
        description="electrons per unit linear radiance; null = auto: the 99.5th "
        "percentile radiance fills 80% of the well",
    )
    response: Literal["linear", "gamma"] = "linear"
    gamma: float = Field(2.2, gt=0)


class RenderCfg(_Model):
    camera: CameraCfg = Field(default_factory=OrthoNadirCfg)
    light: LightCfg = Field(default_factory=SunLightCfg)
    bsdf: BsdfCfg = Field(default_factory=lambda: OrenNayarCfg(kind="oren_nayar"))
    ambient_radiance: float = Field(0.0, ge=0, description="constant sky radiance (0 = off)")
    spp: int = Field(16, ge=1, le=4096)
    max_depth: int = Field(3, ge=2, le=16, description="path depth (2 = direct light only)")
    sensor: SensorCfg | None = Field(
        default_factory=SensorCfg, description="null = use noiseless radiance"
    )


# --------------------------------------------------------------------------- studies
class DensityRange(_Model):
    """``count`` densities log-spaced from ``from`` to ``to`` (ends included)."""

    start: Density = Field(alias="from")
    stop: Density = Field(alias="to")
    count: int = Field(ge=1, le=64)

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=False)

    def values(self) -> list[float]:
        return log_spaced(self.start, self.stop, self.count)


def _densities(value):
    if isinstance(value, dict):
        return DensityRange.model_validate(value).values()
    return value


class SamplingStudyCfg(_Model):
    """The sampling study of the paper's section 4."""

    kind: Literal["sampling"] = "sampling"
    strategies: list[str] = Field(
        default_factory=lambda: ["random", "grid", "gradient", "entropy", "wavelet"], min_length=1
    )
    densities: Annotated[list[Density], BeforeValidator(_densities)] = Field(min_length=1)
    trials: int = Field(20, ge=1, le=1000)
    metrics: list[str] = Field(default_factory=lambda: ["mse", "grad", "sal"], min_length=1)
    range_noise_std_m: Metres = Field(0.0, ge=0, description="range-sensor noise (m)")
    strategy_options: dict[str, dict[str, Any]] = Field(default_factory=dict)
    terrain_seeds: int = Field(
        1,
        ge=1,
        le=100,
        description="repeat every sweep point on this many terrain realisations "
        "(terrain.seed_index 0..N-1, one unit each, all else shared); tables pool them "
        "and give 95 % bootstrap intervals",
    )

    @field_validator("strategies", "metrics")
    @classmethod
    def _unique(cls, v: list[str]) -> list[str]:
        if len(set(v)) != len(v):
            raise ValueError(f"names must be unique, got {v}")
        return v


class ScannerStudyCfg(_Model):
    """The structured-light scanner study of the paper's section 5
    (:func:`simlunar.study.scanner.run_scanner_study`)."""

    kind: Literal["scanner"]
    modes: list[str] = Field(
        default_factory=lambda: ["gray_code", "ambiguity_enhancement"],
        min_length=1,
        description="scan modes: gray_code, ambiguity_enhancement, data_reduction, ...",
    )
    planners: list[str] = Field(
        default_factory=lambda: ["wavelet", "random"],
        min_length=1,
        description="strategies that pick the dots (dot modes)",
    )
    budget: Density = Field(0.1, description="fraction of guide pixels rescanned / sampled")
    trials: int = Field(1, ge=1, le=100)
    metrics: list[str] = Field(default_factory=lambda: ["mse", "grad", "sal"], min_length=1)
    rig: Literal["moonyard", "aerial"] = Field("moonyard", description="rig preset")
    projector_px: tuple[int, int] = Field((256, 192), description="projector (width, height)")
    camera_px: tuple[int, int] = Field((256, 192), description="camera (width, height)")
    guide_light: Literal["projector", "sun"] = Field(
        "projector", description="guide image light: camera-centred projector or render.light"
    )
    projector_gamma: float = Field(1.0, gt=0)
    projector_blur_px: float = Field(0.0, ge=0, description="projector defocus sigma (px)")
    camera_blur_px: float = Field(
        0.0, ge=0, description="camera lens point-spread function, Gaussian sigma (camera px)"
    )
    options: dict[str, Any] = Field(
        default_factory=dict,
        description="extra keyword options of run_scanner_study "
        "(gray_opts, dot_opts, planner_opts, rig keywords under 'rig')",
    )


StudyCfg = _tagged_union("sampling", SamplingStudyCfg, ScannerStudyCfg)


class FiguresCfg(_Model):
    enabled: bool = True
    formats: list[Literal["png", "pdf"]] = Field(default_factory=lambda: ["png", "pdf"])
    panel_density: Density = Field(1 / 64, description="density shown in the image panels")
    sparse_mesh_density: Density | None = Field(
        1 / 80,
        description="Fig. 4: render the mesh reconstructed from this density of "
        "wavelet-planned samples (paper: 80x reduction); null = skip",
    )
    sparse_mesh_sigma_deg: tuple[Deg, Deg] | None = Field(
        (20.0, 45.0),
        description="Fig. 4: Oren-Nayar roughness range [min, max] that the normalised "
        "wavelet energy maps to per cell of the sparse mesh (oren_nayar scenes only); "
        "null = no roughness-modulated render",
    )
    sparse_mesh_roughness_threshold: float | None = Field(
        0.8,
        gt=0,
        le=1,
        description="Fig. 4: normalised wavelet energy at and above which the sparse mesh "
        "is kept metric (those cells get the minimum roughness); null = no threshold",
    )

    @field_validator("sparse_mesh_sigma_deg")
    @classmethod
    def _sigma_range(cls, v):
        if v is not None and not (0.0 <= v[0] <= v[1] < 90.0):
            raise ValueError(f"must satisfy 0 <= min <= max < 90 degrees, got {list(v)}")
        return v

    @property
    def sparse_mesh_sigma(self) -> tuple[float, float] | None:
        """The roughness range in radians (None = no modulated render)."""
        if self.sparse_mesh_sigma_deg is None:
            return None
        lo, hi = self.sparse_mesh_sigma_deg
        return math.radians(lo), math.radians(hi)


class ExperimentCfg(_Model):
    """One experiment: a scene, a study, and optional sweep axes (cartesian product)."""

    name: str = Field(pattern=r"^[A-Za-z0-9_.-]+$")
    description: str = ""
    seed: int = Field(0, ge=0, lt=2**31)
    terrain: TerrainCfg
    render: RenderCfg = Field(default_factory=RenderCfg)
    study: StudyCfg
    sweep: dict[str, list[Any]] = Field(
        default_factory=dict,
        description="dotted key path -> values; the cartesian product becomes work units",
    )
    figures: FiguresCfg = Field(default_factory=FiguresCfg)
