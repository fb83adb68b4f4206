"""The configuration schema: typed pydantic v2 models of experiment, scene and preset YAMLs.

One set of models: an experiment (:class:`ExperimentCfg`), a scene YAML
(:class:`simlunar.config.scene.SceneCfg`, built from the same sections) and a terrain preset
file (:class:`TerrainPresetCfg`, whose sections an experiment's ``terrain.overrides`` changes).
Every YAML key is a field, option blocks included (no free-form dicts); unknown keys are
rejected everywhere (``extra="forbid"``) and numbers must be finite. Keys carry their unit as a
suffix (``_deg``, ``_m``, ``_px``); values may be plain numbers in that unit or strings with an
explicit unit (``"0.5 rad"``, ``"20 cm"``), converted once here. Properties without the suffix
(``SunLightCfg.elevation``) give radians; :mod:`simlunar.config.translate` turns the models
into library objects. Loading, key-path error messages and sweeps live in
:mod:`simlunar.config.loading`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal, Optional, Union

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    JsonValue,
    PositiveInt,
    StringConstraints,
    Tag,
    create_model,
    field_validator,
    model_serializer,
    model_validator,
)

from simlunar.config.quantities import log_spaced, parse_fraction, parse_quantity

#: what a unit-bearing key accepts in the YAML (for the editor schema): a number in the key's
#: unit or a string with an explicit unit ("0.5 rad", "20 cm")
_QUANTITY_INPUT = float | Annotated[str, StringConstraints(pattern=r"^\s*[-+]?[0-9.]")]
_FRACTION_INPUT = (
    float | Annotated[str, StringConstraints(pattern=r"^\s*[0-9.]+(\s*/\s*[0-9.]+)?\s*$")]
)

Deg = Annotated[
    float,
    BeforeValidator(lambda v: parse_quantity(v, "deg"), json_schema_input_type=_QUANTITY_INPUT),
]
Metres = Annotated[
    float,
    BeforeValidator(lambda v: parse_quantity(v, "m"), json_schema_input_type=_QUANTITY_INPUT),
]
Density = Annotated[float, BeforeValidator(parse_fraction, json_schema_input_type=_FRACTION_INPUT)]
Px = Annotated[float, Field(ge=0)]


class _Model(BaseModel):
    # finite numbers only: .inf / .nan in a YAML is a one-line error with its key path
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class _SetKeysModel(_Model):
    """Serialises the keys that are set (not None) only: an override names what it changes."""

    @model_serializer(mode="wrap")
    def _set_keys_only(self, handler):
        return {k: v for k, v in handler(self).items() if v is not None}


def _partial(model: type[BaseModel]) -> type[BaseModel]:
    """``model`` with every field optional (default None = keep the value it overrides)."""
    fields = {}
    for name, f in model.model_fields.items():
        info = f._copy()
        info.default = None
        info.default_factory = None
        fields[name] = (Optional[f.annotation], info)  # noqa: UP045 - runtime type
    return create_model(
        f"{model.__name__}Override",
        __base__=_SetKeysModel,
        __doc__=f"Overrides of {model.__name__} (unset keys keep the preset's value).",
        **fields,
    )


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
# The terrain preset files (scenes/aerial_1.yaml, ...) and an experiment's terrain.overrides use
# these models; :mod:`simlunar.config.translate` turns them into
# :class:`simlunar.terrain.params.TerrainParams`. Defaults are the terrain package's.
def _check_law(kind: str, law: str, coefficient, exponent) -> None:
    from simlunar.terrain.sfd import get_law

    get_law(kind, law, coefficient=coefficient, exponent=exponent)


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


class CratersCfg(_Model):
    """Crater population: cumulative size-frequency law, diameter range, degradation."""

    enabled: bool = True
    law: str = Field("trask", description="trask, viper or power (then coefficient, exponent)")
    d_min_m: Metres = Field(1.0, gt=0)
    d_max_m: Metres = Field(30.0, gt=0)
    coefficient: float | None = Field(None, gt=0, description="power law: N(>D) = c D^-e per m^2")
    exponent: float | None = Field(None, gt=0)
    diffusivity_m2_per_myr: float = Field(5.5, ge=0, description="topographic diffusion")
    max_age_myr: float = Field(20.0, ge=0)

    @model_validator(mode="after")
    def _range_and_law(self):
        if self.d_max_m <= self.d_min_m:
            raise ValueError(
                f"d_max_m: the diameter range is empty ({self.d_max_m} <= d_min_m {self.d_min_m})"
            )
        _check_law("craters", self.law, self.coefficient, self.exponent)
        return self


class RocksCfg(_Model):
    """Rock population: cumulative law, diameter range, clustering, albedo contrast."""

    enabled: bool = True
    law: str = Field("intercrater", description="a rock law name or power")
    d_min_m: Metres = Field(0.3, gt=0)
    d_max_m: Metres = Field(3.0, gt=0)
    coefficient: float | None = Field(None, gt=0)
    exponent: float | None = Field(None, gt=0)
    cluster_fraction: float = Field(0.5, ge=0, le=1)
    cluster_radius_m: Metres = Field(3.0, gt=0)
    mean_per_cluster: float = Field(8.0, ge=1)
    albedo_contrast: float = Field(0.1, ge=-0.9, le=5)

    @model_validator(mode="after")
    def _range_and_law(self):
        if self.d_max_m <= self.d_min_m:
            raise ValueError(
                f"d_max_m: the diameter range is empty ({self.d_max_m} <= d_min_m {self.d_min_m})"
            )
        _check_law("rocks", self.law, self.coefficient, self.exponent)
        return self


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

    preset: str | None = Field(None, description="terrain preset name, e.g. aerial_1, moonyard")
    scale: float = Field(1.0, gt=0, le=1, description="preset resolution scale (1/8 = small)")
    file: Path | None = Field(None, description="DEM file (.npy, .tif, .exr); relative to the YAML")
    spacing_m: Metres | None = Field(
        None, gt=0, description="DEM cell size (m), for a file without georeferencing"
    )
    albedo_file: Path | None = Field(
        None, description="albedo grid file (.npy, same shape as the DEM), for file"
    )
    albedo: float | None = Field(
        None, ge=0, le=1, description="replace the albedo by this uniform value (ablation)"
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
            from simlunar.config.presets import PresetError, merged_preset

            try:
                merged_preset(self.preset, self.overrides)
            except PresetError as exc:
                if exc.key is not None:
                    raise ValueError(f"overrides.{exc.key}: {exc.problem}") from None
                raise ValueError(f"preset: {exc.problem}") from None
        if self.file is not None and self.seed_index != 0:
            raise ValueError("seed_index applies to a preset only (a DEM file has one terrain)")
        return self


# --------------------------------------------------------------------------- render
class OrthoNadirCfg(_Model):
    """Orthographic nadir camera whose pixel (r, c) sees DEM cell (r, c) (aerial view)."""

    kind: Literal["orthographic_nadir"] = "orthographic_nadir"
    altitude_m: Metres = Field(50.0, gt=0, description="camera height above z = 0 (m)")


Vec3 = tuple[float, float, float]


class PerspectiveCfg(_Model):
    """Pinhole (or thin-lens) camera at ``position_m`` looking at ``look_at_m``.

    Give either ``fov_deg`` (horizontal; square pixels, centred principal point) or all of
    ``fx, fy, cx, cy`` (pixels; pixel centres at i + 0.5, so centred is ``width/2``).
    """

    kind: Literal["perspective"]
    width: int = Field(gt=0, le=16384)
    height: int = Field(gt=0, le=16384)
    fov_deg: Deg | None = Field(None, gt=0, lt=180, description="horizontal field of view")
    fx: float | None = Field(None, gt=0, description="focal length (px)")
    fy: float | None = Field(None, gt=0, description="focal length (px)")
    cx: float | None = Field(None, description="principal point (px)")
    cy: float | None = Field(None, description="principal point (px)")
    position_m: Vec3
    look_at_m: Vec3
    up: Vec3 = Field((0.0, 0.0, 1.0), description="world up direction (unit-free)")
    aperture_radius_m: Metres = Field(0.0, ge=0, description="thin lens; 0 = pinhole")
    focus_distance_m: Metres | None = Field(None, gt=0)

    @model_validator(mode="after")
    def _intrinsics(self) -> PerspectiveCfg:
        k = [self.fx, self.fy, self.cx, self.cy]
        if self.fov_deg is None and any(v is None for v in k):
            raise ValueError("give fov_deg or all of fx, fy, cx, cy")
        if self.fov_deg is not None and any(v is not None for v in k):
            raise ValueError("give fov_deg or fx, fy, cx, cy, not both")
        if self.aperture_radius_m > 0 and self.focus_distance_m is None:
            raise ValueError("a thin lens (aperture_radius_m > 0) needs focus_distance_m")
        if tuple(self.position_m) == tuple(self.look_at_m):
            raise ValueError("look_at_m: equals position_m (the camera looks at its own position)")
        return self


class RoverMastCfg(_Model):
    """Perspective camera on a rover mast: ``height_m`` above the ground at ``site_m``, its
    optical axis ``depression_deg`` below the horizon, towards ``azimuth_deg``."""

    kind: Literal["rover_mast"]
    width: int = Field(320, gt=0, le=16384)
    height: int = Field(240, gt=0, le=16384)
    fov_deg: Deg = Field(60.0, gt=0, lt=180, description="horizontal field of view")
    height_m: Metres = Field(1.5, gt=0, description="camera height above the terrain at the site")
    depression_deg: Deg = Field(
        30.0, gt=0, le=90, description="optical axis below the horizon (90 = straight down)"
    )
    azimuth_deg: Deg = Field(0.0, description="look direction from +y (north) clockwise to +x")
    site_m: tuple[float, float] | None = Field(
        None, description="world (x, y) of the mast foot; default the terrain's centre"
    )


CameraCfg = _tagged_union("orthographic_nadir", OrthoNadirCfg, PerspectiveCfg, RoverMastCfg)


class SunLightCfg(_Model):
    """A distant sun. Azimuth from +y (north) clockwise towards +x (east)."""

    kind: Literal["sun"] = "sun"
    elevation_deg: Deg = Field(30.0, gt=0, le=90, description="above the horizon (0 < e <= 90)")
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

    @property
    def angular_diameter(self) -> float:
        return math.radians(self.angular_diameter_deg)


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
    sigma_deg: Deg = Field(20.0, ge=0, lt=90, description="slope standard deviation (< 90)")
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
        description="electrons per unit linear radiance; null = auto exposure: the 99.5th "
        "percentile of the reference radiance fills 80% of the full well (the guide image; "
        "the white calibration frame in scanner studies)",
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

    model_config = ConfigDict(
        extra="forbid", frozen=True, populate_by_name=False, allow_inf_nan=False
    )

    def values(self) -> list[float]:
        return log_spaced(self.start, self.stop, self.count)


def _densities(value):
    if isinstance(value, dict):
        return DensityRange.model_validate(value).values()
    return value


# Planner options. Defaults are the library's (a test compares them with the signatures of
# simlunar.planner / simlunar.features); the translation passes them to the weighted strategies.
#: the feature-map options each weighted strategy's map takes
FEATURE_OPTION_KEYS = {
    "uniform": (),
    "gradient": (),
    "saliency": (),
    "entropy": ("size", "scale"),
    "wavelet": ("wavelet", "levels", "boundary"),
}


class FeatureOptsCfg(_Model):
    """Options of the strategy's importance map (:func:`simlunar.features.feature_map`).

    ``wavelet``, ``levels``, ``boundary`` belong to the wavelet map; ``size``, ``scale`` to the
    entropy map. A ``combination`` passes each map the options that belong to it.
    """

    wavelet: str = Field("db2", description="wavelet map: PyWavelets wavelet name")
    levels: PositiveInt | None = Field(
        None, description="wavelet map: decomposition levels summed, finest first; null = all"
    )
    boundary: Literal["symmetric", "periodic"] = Field("symmetric", description="wavelet map")
    size: PositiveInt = Field(9, description="entropy map: window side (px)")
    scale: Literal["minmax", "unit"] = Field("minmax", description="entropy map: 8-bit scaling")

    @field_validator("wavelet")
    @classmethod
    def _known_wavelet(cls, v: str) -> str:
        import pywt

        if v not in pywt.wavelist(kind="discrete"):
            raise ValueError(f"unknown discrete wavelet {v!r} (e.g. db2, haar, sym4)")
        return v


class CoefficientsCfg(_Model):
    """``combination`` strategy: the weight of each feature map (maps normalised to mean 1;
    ``uniform`` is the constant map)."""

    uniform: float | None = Field(None, ge=0)
    gradient: float | None = Field(None, ge=0)
    entropy: float | None = Field(None, ge=0)
    wavelet: float | None = Field(None, ge=0)
    saliency: float | None = Field(None, ge=0)

    def as_mapping(self) -> dict[str, float]:
        return {k: v for k, v in self.model_dump().items() if v is not None}


class PlannerOptsCfg(_Model):
    """Options of a feature-weighted strategy (:func:`simlunar.planner.plan`)."""

    uniform_mix: float = Field(0.0, ge=0, le=1, description="mixture with uniform sampling")
    density_cap: float | None = Field(
        None, ge=1, description="max regional density, a multiple of the mean; null = none"
    )
    cap_block: PositiveInt = Field(16, description="block side (px) of density_cap")
    blue_noise: bool = Field(False, description="Poisson-disk-like weighted sampling")
    blue_noise_radius: float = Field(0.5, gt=0, description="radius factor of blue_noise")
    feature_opts: FeatureOptsCfg = Field(default_factory=FeatureOptsCfg)
    coefficients: CoefficientsCfg = Field(
        default_factory=CoefficientsCfg, description="combination only: map weights"
    )


class StrategyOptionsCfg(PlannerOptsCfg):
    """A strategy label's options: ``strategy`` names the registered strategy (default: the
    label itself), the rest are its planner options."""

    strategy: str | None = Field(None, description="registered strategy; null = the label")


def check_planner_options(base: str, opts: PlannerOptsCfg) -> None:
    """Raise ``ValueError("<key>: problem")`` for options the strategy ``base`` does not take."""
    default = PlannerOptsCfg()
    changed = [k for k in PlannerOptsCfg.model_fields if getattr(opts, k) != getattr(default, k)]
    if base in ("grid", "random"):
        if changed:
            raise ValueError(f"{changed[0]}: strategy {base!r} takes no options")
        return
    if base == "combination":
        if not opts.coefficients.as_mapping():
            raise ValueError("coefficients: strategy 'combination' needs at least one weight")
        features = list(opts.coefficients.as_mapping())
    else:
        if "coefficients" in changed:
            raise ValueError(f"coefficients: only the combination strategy takes them ({base!r})")
        features = [base]
    allowed = {k for f in features for k in FEATURE_OPTION_KEYS.get(f, ())}
    fdefault = FeatureOptsCfg()
    for k in FeatureOptsCfg.model_fields:
        if getattr(opts.feature_opts, k) != getattr(fdefault, k) and k not in allowed:
            raise ValueError(
                f"feature_opts.{k}: not an option of the {'/'.join(features)} map "
                f"(valid: {', '.join(sorted(allowed)) or 'none'})"
            )


class SamplingStudyCfg(_Model):
    """The sampling study of the paper's section 4."""

    kind: Literal["sampling"] = "sampling"
    strategies: list[str] = Field(
        default_factory=lambda: ["random", "grid", "gradient", "entropy", "wavelet"], min_length=1
    )
    densities: Annotated[
        list[Density],
        BeforeValidator(_densities, json_schema_input_type=list[Density] | DensityRange),
    ] = Field(min_length=1)
    trials: int = Field(20, ge=1, le=1000)
    metrics: list[str] = Field(default_factory=lambda: ["mse", "grad", "sal"], min_length=1)
    range_noise_std_m: Metres = Field(0.0, ge=0, description="range-sensor noise (m)")
    strategy_options: dict[str, StrategyOptionsCfg] = Field(
        default_factory=dict,
        description="label -> options; a label not registered as a strategy names one in "
        "'strategy' (e.g. wavelet_bn: {strategy: wavelet, blue_noise: true})",
    )
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

    @model_validator(mode="after")
    def _options_fit(self) -> SamplingStudyCfg:
        from simlunar.planner import STRATEGIES

        for label, opts in self.strategy_options.items():
            base = opts.strategy or label
            if base not in STRATEGIES:
                continue  # reported with the registries (unknown strategy, with its path)
            try:
                check_planner_options(base, opts)
            except ValueError as exc:
                raise ValueError(f"strategy_options.{label}.{exc}") from None
        return self


class RigCfg(_Model):
    """Adjustments of the rig preset (:mod:`simlunar.scanner.rigs`); null = the preset's."""

    fill: float = Field(0.9, gt=0, le=1, description="projection footprint / terrain side")
    fov_x_deg: Deg | None = Field(
        None,
        gt=0,
        lt=180,
        description="projector horizontal field of view (50 moonyard, 30 aerial)",
    )
    cam_fov_x_deg: Deg | None = Field(
        None, gt=0, lt=180, description="triangulation camera field of view; null = projector's"
    )
    distance_m: Metres | None = Field(
        None, gt=0, description="moonyard: projector standoff; null = fit the terrain"
    )
    altitude_m: Metres | None = Field(
        None, gt=0, description="aerial: projector altitude; null = fit the terrain"
    )
    elevation_deg: Deg | None = Field(
        None, gt=0, le=90, description="moonyard: projector elevation (default 70)"
    )
    azimuth_deg: Deg | None = Field(None, ge=-360, le=360, description="projector azimuth")
    baseline_m: Metres | None = Field(
        None, gt=0, description="camera offset; null = 0.25 (moonyard) / 0.15 (aerial) x standoff"
    )
    verge: bool = Field(True, description="camera verged on the target")
    aperture_radius_m: Metres = Field(0.0, ge=0, description="camera thin lens; 0 = pinhole")
    focus_distance_m: Metres | None = Field(None, gt=0, description="null = the target")


class GrayOptsCfg(_Model):
    """Gray-code scan options (:func:`simlunar.scanner.modes.gray_code_scan`)."""

    black_threshold: float = Field(0.05, ge=0, le=1, description="validity (frame units)")
    white_threshold: float = Field(0.01, ge=0, le=1, description="bit reliability (frame units)")
    inverses: Literal["linearity", "render"] = "linearity"
    method: Literal["plane", "rays"] = "plane"
    require_reliable: bool = True
    subpixel: bool = Field(False, description="sub-pixel stripe-edge refinement")


class DotOptsCfg(_Model):
    """Dot scan options (:func:`simlunar.scanner.modes.dot_scan`)."""

    exact: bool = Field(False, description="one dot per frame (reference mode)")
    radius_px: Px = Field(0.0, description="dot radius (projector px); 0 = one pixel")
    min_proj_spacing_px: Px = Field(8.0, description="scheduling spacing (projector px)")
    min_cam_spacing_px: Px = Field(6.0, description="scheduling spacing (camera px)")
    tol_px: Px = Field(2.0, description="matching tolerance (camera px)")
    rel_threshold: float = Field(0.02, ge=0, le=1, description="relative blob threshold")
    abs_threshold: float = Field(0.02, ge=0, le=1, description="absolute blob threshold")
    batch: PositiveInt = Field(8, description="frames per render call (memory only)")


class CaptureOptsCfg(_Model):
    """Render-capture options (:class:`simlunar.render.capture.RenderCapture`)."""

    sparse_integrator: Literal["path", "ptracer"] = Field(
        "path",
        description="integrator for sparse patterns (dot frames): path tracer, or ptracer "
        "(light traced from the projector; docs/scanner.md)",
    )
    sparse_spp: PositiveInt | None = Field(
        None, description="samples per pixel for sparse patterns (null: render.spp)"
    )
    sparse_below: float = Field(
        0.01, gt=0, le=1, description="largest lit fraction of projector pixels counted sparse"
    )


class ScannerOptionsCfg(_Model):
    """Scanner study options: rig adjustments, gray-code, dot scan and capture options,
    planner options."""

    rig: RigCfg = Field(default_factory=RigCfg)
    gray_opts: GrayOptsCfg = Field(default_factory=GrayOptsCfg)
    dot_opts: DotOptsCfg = Field(default_factory=DotOptsCfg)
    capture_opts: CaptureOptsCfg = Field(default_factory=CaptureOptsCfg)
    planner_opts: dict[str, PlannerOptsCfg] = Field(
        default_factory=dict, description="planner name -> options (study.planners only)"
    )


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
        description="what picks the dots (dot modes): a planner strategy (from the guide "
        "image) or low_contrast (the gray-code pixels the projector lit least; "
        "ambiguity_enhancement only)",
    )
    budget: Density = Field(0.1, description="fraction of guide pixels rescanned / sampled")
    trials: int = Field(1, ge=1, le=100)
    metrics: list[str] = Field(default_factory=lambda: ["mse", "grad", "sal"], min_length=1)
    rig: Literal["moonyard", "aerial"] = Field("moonyard", description="rig preset")
    projector_px: tuple[PositiveInt, PositiveInt] = Field(
        (256, 192), description="projector (width, height)"
    )
    camera_px: tuple[PositiveInt, PositiveInt] = Field(
        (256, 192), description="camera (width, height)"
    )
    guide_light: Literal["projector", "sun"] = Field(
        "projector", description="guide image light: camera-centred projector or render.light"
    )
    scan_light: Literal["none", "sun"] = Field(
        "none",
        description="light on during the scan besides the projector: none (a dark scan, as in "
        "the paper's lab) or sun (render.light, which must be a sun, and "
        "render.ambient_radiance stay on: a daylight scan; docs/scanner.md)",
    )
    projector_gamma: float = Field(1.0, gt=0)
    projector_blur_px: float = Field(0.0, ge=0, description="projector defocus sigma (px)")
    camera_blur_px: float = Field(
        0.0, ge=0, description="camera lens point-spread function, Gaussian sigma (camera px)"
    )
    options: ScannerOptionsCfg = Field(
        default_factory=ScannerOptionsCfg,
        description="rig adjustments (rig), gray_opts, dot_opts, planner_opts",
    )
    save_scans: bool = Field(
        False,
        description="write scans/unit<i>/ per unit: gray-code frames (8/16-bit PNG, OpenCV "
        "order), decoded maps (EXR), point cloud (PLY), OpenCV calibration (docs/scanner.md)",
    )

    @model_validator(mode="after")
    def _scans_need_gray_code(self):
        if self.save_scans and not {"gray_code", "ambiguity_enhancement"} & set(self.modes):
            raise ValueError(
                "save_scans exports the gray-code scan: modes must include gray_code or "
                "ambiguity_enhancement"
            )
        return self

    @model_validator(mode="after")
    def _options_fit(self) -> ScannerStudyCfg:
        from simlunar.planner import STRATEGIES

        o = self.options
        stray = sorted(set(o.planner_opts) - set(self.planners))
        if stray:
            raise ValueError(
                f"options.planner_opts.{stray[0]}: not in study.planners ({', '.join(self.planners)})"
            )
        from simlunar.scanner.modes import SCAN_PLANNERS

        scan_planners = [p for p in self.planners if p in SCAN_PLANNERS]
        if scan_planners and "data_reduction" in self.modes:
            raise ValueError(
                f"planners: {scan_planners[0]} ranks the pixels of the gray-code scan, which "
                "the data_reduction mode does not make (use it with ambiguity_enhancement)"
            )
        for name in scan_planners:
            if name in o.planner_opts:
                raise ValueError(f"options.planner_opts.{name}: {name} takes no options")
        for name, opts in o.planner_opts.items():
            if name in STRATEGIES:
                try:
                    check_planner_options(name, opts)
                except ValueError as exc:
                    raise ValueError(f"options.planner_opts.{name}.{exc}") from None
        moonyard_only = ("distance_m", "elevation_deg")
        aerial_only = ("altitude_m",)
        for key in aerial_only if self.rig == "moonyard" else moonyard_only:
            if getattr(o.rig, key) is not None:
                raise ValueError(f"options.rig.{key}: not an option of the {self.rig} rig")
        return self


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
    sweep: dict[str, list[JsonValue]] = Field(
        default_factory=dict,
        description="dotted key path -> values; the cartesian product becomes work units "
        "(each point is validated against this schema; unit strings become numbers)",
    )
    figures: FiguresCfg = Field(default_factory=FiguresCfg)

    @model_validator(mode="after")
    def _study_fits_render(self) -> ExperimentCfg:
        sensor = self.render.sensor
        if (
            isinstance(self.study, ScannerStudyCfg)
            and sensor is not None
            and sensor.exposure_e is not None
        ):
            raise ValueError(
                "render.sensor.exposure_e: a scanner study sets the exposure from its white "
                "calibration frame (the auto exposure); leave exposure_e null"
            )
        if isinstance(self.study, ScannerStudyCfg) and not isinstance(
            self.render.light, SunLightCfg
        ):
            for key in ("guide_light", "scan_light"):
                if getattr(self.study, key) == "sun":
                    raise ValueError(
                        f"study.{key}: sun needs render.light.kind sun (got "
                        f"{self.render.light.kind})"
                    )
        return self
