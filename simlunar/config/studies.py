"""Study sections of the schema: the sampling study (paper section 4), the scanner study
(section 5) and the image-directed LIDAR study (its sensor options in :mod:`simlunar.config.lidar`)."""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import (
    BeforeValidator,
    ConfigDict,
    Field,
    create_model,
    field_validator,
    model_validator,
)

from simlunar.config.derived import ComponentList, options_model, reconstruction_specs
from simlunar.config.fields import (
    Density,
    Metres,
    _Model,
    unique_names,
)
from simlunar.config.landing import LandingCfg
from simlunar.config.lidar import HazardCfg, LidarOptionsCfg, LidarPlannerOptsCfg, SafeSiteCfg
from simlunar.config.planners import (  # noqa: F401 - the schema's planner models live there
    CoefficientsCfg,
    FeatureOptsCfg,
    OracleOptsCfg,
    PlannerOptions,
    PlannerOptsCfg,
    SequentialCfg,
    StrategyOptions,
    StrategyOptionsCfg,
    check_planner_options,
    own_placements,
)
from simlunar.config.quantities import log_spaced
from simlunar.planner import (
    DEFAULT_PLANNER,
    MEASURING,
    ORACLES,
    PAPER_STRATEGIES,
    STRATEGIES,
)
from simlunar.reconstruction import RECONSTRUCTIONS
from simlunar.study.reconstruction_spec import parse_reconstructions

__all__ = [
    "LIDAR_BLOCKS",
    "DensityRange",
    "FeatureOptsCfg",
    "LidarStudyCfg",
    "PlannerOptsCfg",
    "Reconstructions",
    "SamplingStudyCfg",
    "check_planner_options",
]


#: ``study.reconstructions``: names of :data:`simlunar.reconstruction.RECONSTRUCTIONS` or
#: ``{name: {options}}`` mappings, the options' schema derived from each entry's options class
#: (:func:`simlunar.config.derived.reconstruction_specs`)
def _reconstructions_input_type():
    """The editor schema of ``study.reconstructions``: each registered name, or ``{name:
    {options}}`` with that entry's derived options schema (names registered later are still
    validated, by :func:`~simlunar.config.derived.reconstruction_specs`)."""
    names = RECONSTRUCTIONS.names()
    items = [Literal[names]]
    for n in names:
        model = options_model(RECONSTRUCTIONS[n].options, f"reconstruction {n}")
        items.append(dict[Literal[n], model])
        # {label: {reconstruction: n, options}}: the same reconstruction under a label of its own
        labelled = create_model(
            f"Labelled{model.__name__}",
            __base__=model,
            reconstruction=(Literal[n], Field(description="the registered reconstruction")),
        )
        items.append(dict[str, labelled])
    return list[Union[tuple(items)]]  # noqa: UP007 - built at run time


Reconstructions = Annotated[
    list,
    BeforeValidator(reconstruction_specs, json_schema_input_type=_reconstructions_input_type()),
    ComponentList(RECONSTRUCTIONS, "reconstruction"),
]


def _save_arrays_field():
    return Field(
        False,
        description="write arrays/unit<i>/ per unit: trial 0's reconstruction of every "
        "planner, density and reconstruction and its error map (reconstruction - truth), "
        "GeoTIFF and EXR (docs/experiments.md); changes no number",
    )


def _reconstructions_field():
    return Field(
        default_factory=lambda: ["linear"],
        description="reconstructions run on every acquisition, each scored: a name or "
        "{name: {options}} (linear: the paper's Delaunay-linear; guided ones read the guide "
        "frames of render.guide_frames)",
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


class SamplingStudyCfg(_Model):
    """The sampling study of the paper's section 4."""

    kind: Literal["sampling"] = "sampling"
    # the YAML default lists random first (the row order of every run without the key)
    strategies: list[str] = Field(
        default_factory=lambda: ["random", "grid", *PAPER_STRATEGIES[2:]], min_length=1
    )
    densities: Annotated[
        list[Density],
        BeforeValidator(_densities, json_schema_input_type=list[Density] | DensityRange),
    ] = Field(min_length=1)
    trials: int = Field(20, ge=1, le=1000)
    metrics: list[str] = Field(default_factory=lambda: ["mse", "grad", "sal"], min_length=1)
    range_noise_std_m: Metres = Field(0.0, ge=0, description="range-sensor noise (m)")
    strategy_options: StrategyOptions = Field(
        default_factory=dict,
        description="label -> options; a label not registered as a strategy names one in "
        "'strategy' (e.g. wavelet_bn: {strategy: wavelet, blue_noise: true})",
    )
    score_region: Literal["full", "interior", "both"] = Field(
        "full",
        description="score the full image, the interior (cells farther than the sparsest "
        "density's pitch from the border: no extrapolation; metrics named <metric>_interior) "
        "or both",
    )
    terrain_seeds: int = Field(
        1,
        ge=1,
        le=100,
        description="repeat every sweep point on this many terrain realisations "
        "(terrain.seed_index 0..N-1, one unit each, all else shared); tables pool them "
        "and give 95 % bootstrap intervals",
    )
    reconstructions: Reconstructions = _reconstructions_field()
    save_arrays: bool = _save_arrays_field()

    _unique = field_validator("strategies", "metrics")(unique_names)

    def _reconstruction_labels(self) -> list[str]:
        """The labels of ``reconstructions`` (a name, or the one key of a mapping)."""
        return [spec.label for spec in parse_reconstructions(self.reconstructions)]

    @model_validator(mode="after")
    def _options_fit(self) -> SamplingStudyCfg:

        for label in [*self.strategy_options, *self.strategies]:
            opts = self.strategy_options.get(label)
            base = (opts.strategy if opts is not None else None) or label
            if base not in STRATEGIES and base not in MEASURING:
                continue  # reported with the registries (unknown strategy, with its path)
            if base in ORACLES and not label.startswith("oracle"):
                raise ValueError(
                    f"strategy_options.{label}: a label of an oracle ({base}) starts with "
                    "'oracle', so every table shows it as a bound"
                )
            recon = opts.oracle.reconstruction if opts is not None else "linear"
            if recon != "linear" and recon not in self._reconstruction_labels():
                raise ValueError(
                    f"strategy_options.{label}.oracle.reconstruction: {recon!r} is not one of "
                    f"study.reconstructions ({', '.join(self._reconstruction_labels())})"
                )
            try:
                check_planner_options(base, opts or PlannerOptsCfg())
            except ValueError as exc:
                where = f"strategy_options.{label}" if opts is not None else f"strategies ({label})"
                raise ValueError(f"{where}.{exc}") from None
        return self


#: the LIDARs of a lidar study and the block of ``options`` each reads
LIDAR_BLOCKS = {
    "steered_beam": "steered_beam",
    "flash": "flash",
    "micromirror_flash": "micromirror",
}


class LidarStudyCfg(_Model):
    """Image-directed LIDAR (:func:`simlunar.study.lidar.run_lidar_study`; docs/lidar.md):
    planners -> a time-of-flight sensor at the guide camera -> reconstruction -> scores, every
    row with its modelled scan time (``seconds``)."""

    kind: Literal["lidar"]
    sensor: Literal["steered_beam", "flash", "micromirror_flash"] = Field(
        "steered_beam",
        description="steered_beam (gimbal / galvanometer), flash (receiver array; revisits "
        "directed by the plan) or micromirror_flash (lights only the planned pixels)",
    )
    planners: list[str] = Field(
        default_factory=lambda: [DEFAULT_PLANNER, "random", "grid"],
        min_length=1,
        description="planner strategies (from the guide image; oracle_*: bounds that read the "
        "true depth in the planner step, labels starting 'oracle'; sequential: multi-round, each "
        "round measured by the LIDAR, its time counting every round); unused by a flash without "
        "revisits",
    )
    densities: Annotated[
        list[Density],
        BeforeValidator(_densities, json_schema_input_type=list[Density] | DensityRange),
    ] = Field(
        default_factory=lambda: [1 / 64, 1 / 256],
        min_length=1,
        description="planned pixels k / N of the guide view",
    )
    trials: int = Field(3, ge=1, le=1000, description="planner draws and photon noise")
    metrics: list[str] = Field(default_factory=lambda: ["mse", "grad"], min_length=1)
    planner_opts: Annotated[dict[str, LidarPlannerOptsCfg], BeforeValidator(own_placements)] = (
        Field(
            default_factory=dict,
            description="planner label -> options (study.planners only); a label not registered "
            "as a strategy names one in 'strategy'; 'fit' fits it to the sensor",
        )
    )
    hazard: HazardCfg | None = Field(
        None, description="also score landing-hazard detection (precision / recall); null = off"
    )
    safe_site: SafeSiteCfg | None = Field(
        None,
        description="also score whether the landing site chosen from the reconstruction is "
        "truly safe (safe_site, safe_site_precision, safe_sites_available); null = off",
    )
    landing: LandingCfg | None = Field(
        None,
        description="also score the landing site per hazard size (hazard_recall_rock_<h>cm, "
        "hazard_recall_slope_<s>deg, their precisions, false_safe_site, safe_site_called, "
        "height_rms, slope_rms_deg; docs/landing.md); null = off",
    )
    options: LidarOptionsCfg = Field(
        default_factory=LidarOptionsCfg,
        description="pulse, detector, ranging, transient, and the sensor's own block",
    )
    options_by_sensor: dict[Literal["steered_beam", "flash", "micromirror_flash"],
                            LidarOptionsCfg] = Field(
        default_factory=dict,
        description="sensor -> its options, used as options when study.sensor names it (so a "
        "sweep over study.sensor compares sensors each with its own instrument and block); "
        "options, if also given, must be one of them",
    )  # fmt: skip
    save_scans: bool = Field(
        False,
        description="write scans/unit<i>/ per unit: each planner's example point cloud (LAZ, "
        "PLY; world frame, per-point time, photons, returns) and range images (EXR) "
        "(docs/lidar.md)",
    )
    terrain_seeds: int = Field(
        1,
        ge=1,
        le=100,
        description="repeat every sweep point on this many terrain realisations (intervals "
        "over terrain seeds in the figures)",
    )
    reconstructions: Reconstructions = _reconstructions_field()
    save_arrays: bool = _save_arrays_field()

    _unique = field_validator("planners", "metrics")(unique_names)

    @model_validator(mode="before")
    @classmethod
    def _sensor_options(cls, data):
        """``options`` from ``options_by_sensor`` for the study's sensor (module field doc)."""
        if not isinstance(data, dict) or not data.get("options_by_sensor"):
            return data
        by = data["options_by_sensor"]
        sensor = data.get("sensor", cls.model_fields["sensor"].default)
        if not isinstance(by, dict) or sensor not in by:
            return data
        if data.get("options") is not None:
            # a config written back (or a sweep point of another sensor) holds the options of
            # one of the sensors: replaced; any other options would be silently lost
            given = LidarOptionsCfg.model_validate(data["options"])
            known = [LidarOptionsCfg(), *(LidarOptionsCfg.model_validate(v) for v in by.values())]
            if given not in known:
                raise ValueError(
                    f"options: replaced by options_by_sensor.{sensor}; give the sensor's "
                    "options there only"
                )
        return {**data, "options": by[sensor]}

    @model_validator(mode="after")
    def _options_fit(self) -> LidarStudyCfg:
        mine = LIDAR_BLOCKS[self.sensor]
        default = LidarOptionsCfg()
        for block in LIDAR_BLOCKS.values():
            if block != mine and getattr(self.options, block) != getattr(default, block):
                raise ValueError(
                    f"options.{block}: not an option of the {self.sensor} sensor (set "
                    f"options.{mine})"
                )
        stray = sorted(set(self.planner_opts) - set(self.planners))
        if stray:
            raise ValueError(
                f"planner_opts.{stray[0]}: not in study.planners ({', '.join(self.planners)})"
            )
        for name, opts in self.planner_opts.items():
            base = opts.strategy or name
            if base in STRATEGIES:
                try:
                    check_planner_options(base, opts)
                except ValueError as exc:
                    raise ValueError(f"planner_opts.{name}.{exc}") from None
        return self
