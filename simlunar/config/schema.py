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
from typing import Literal

from pydantic import (
    Field,
    JsonValue,
    field_validator,
    model_validator,
)

from simlunar.config.derived import reconstruction_mapping
from simlunar.config.fields import (  # noqa: F401
    _FRACTION_INPUT,
    _QUANTITY_INPUT,
    Deg,
    Density,
    Metres,
    Px,
    _Model,
    _partial,
    _SetKeysModel,
    _tagged_union,
)
from simlunar.config.lidar import receiver_wh
from simlunar.config.render import (
    GuideFlashFrameCfg,
    OrthoNadirCfg,
    PerspectiveCfg,
    RenderCfg,
    SunLightCfg,
)
from simlunar.config.scanner import ScannerStudyCfg
from simlunar.config.studies import LIDAR_BLOCKS, LidarStudyCfg, SamplingStudyCfg
from simlunar.config.terrain import TerrainCfg

__all__ = ["CatalogueCfg", "ExperimentCfg", "FiguresCfg", "RunTimeCfg", "StudyCfg"]

#: the study of an experiment, chosen by its ``kind``; the kind picks the range sensor
StudyCfg = _tagged_union("sampling", SamplingStudyCfg, ScannerStudyCfg, LidarStudyCfg)


class FiguresCfg(_Model):
    enabled: bool = True
    formats: list[Literal["png", "pdf"]] = Field(
        default_factory=lambda: ["png"],
        min_length=1,
        description="figure files: png (300 dpi); add pdf for vector figures (or run --pdf)",
    )
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


class RunTimeCfg(_Model):
    """One measured run time of a shipped experiment, with the conditions it was measured in
    (the experiment catalogue prints them together; no number without its machine load)."""

    wall_min: float | None = Field(
        None,
        gt=0,
        description="wall-clock minutes of `simlunar run` into an empty result folder, "
        "figures included unless the note says otherwise; null = not re-measured",
    )
    load: str = Field(
        "",
        description="the machine while it ran: cores and 1-minute load average, e.g. "
        "'2 cores, load 1.8-1.9'; required with wall_min",
    )
    note: str = Field(
        "",
        description="what else the number depends on: options (--workers 2), a warm or "
        "empty kernel cache, where it was measured",
    )
    first_run_min: float | None = Field(
        None,
        gt=0,
        description="wall-clock minutes of the same run on a machine whose kernel cache "
        "(DRJIT_CACHE_DIR) is empty: the first run compiles the renderer's kernels",
    )

    @model_validator(mode="after")
    def _load_with_time(self) -> RunTimeCfg:
        if (self.wall_min is not None or self.first_run_min is not None) and not self.load:
            raise ValueError("load: a measured run time needs the machine's load beside it")
        return self


class CatalogueCfg(_Model):
    """What a shipped experiment shows and how long it runs: the rows of the experiment
    catalogue (README, docs/experiments.md), generated from these blocks. Changes no number
    and no cache key."""

    shows: str = Field(
        "", description="what the experiment shows, in a sentence or two (catalogue column)"
    )
    run_time: RunTimeCfg = Field(default_factory=RunTimeCfg)


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
    catalogue: CatalogueCfg = Field(
        default_factory=CatalogueCfg,
        description="the experiment's row of the experiment catalogue (what it shows, its "
        "measured run time); no effect on the run",
    )

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
        if isinstance(self.study, ScannerStudyCfg) and any(
            isinstance(f, GuideFlashFrameCfg) for f in self.render.guide_frames
        ):
            raise ValueError(
                "render.guide_frames: a flash frame is not simulated in a scanner study (its "
                "co-located frame is the projector's flood frame: camera)"
            )
        if (
            isinstance(self.study, ScannerStudyCfg)
            and self.study.guide_light == "projector"
            and "camera" in self.render.guide_frames
        ):
            raise ValueError(
                "render.guide_frames: camera (the projector's flood frame) is the scanner's "
                "guide view already (study.guide_light: projector); use guide_light: sun"
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

    @model_validator(mode="after")
    def _use_flat_needs_a_flat_frame(self) -> ExperimentCfg:
        # use_flat: true asked for explicitly reads the co-located (camera) frame; without
        # one the reconstruction ran sun-only without a word
        if "camera" in self.render.guide_frames:
            return self
        for label, opts in reconstruction_mapping(self.study.reconstructions).items():
            if opts.get("use_flat") is True:
                raise ValueError(
                    f"study.reconstructions: {label}: use_flat: true divides by the "
                    "co-located frame, but render.guide_frames has no camera frame (add camera "
                    "to render.guide_frames, or leave use_flat out)"
                )
        return self

    @model_validator(mode="after")
    def _lidar_fits_camera(self) -> ExperimentCfg:
        s, cam = self.study, self.render.camera
        if not isinstance(s, LidarStudyCfg):
            return self
        if isinstance(cam, OrthoNadirCfg) or getattr(cam, "aperture_radius_m", 0.0) > 0:
            raise ValueError(
                "render.camera: a lidar study needs a perspective pinhole camera (the sensor "
                "sits at its centre): kind perspective or rover_mast"
            )
        if s.sensor == "steered_beam":
            return self
        block = LIDAR_BLOCKS[s.sensor]
        rw, rh = receiver_wh(s.options, block)
        if round(cam.height * rw / cam.width) != rh:
            raise ValueError(
                f"study.options.{block}.receiver_px: ({rw}, {rh}) must keep the camera's "
                f"aspect ({cam.width} x {cam.height}), e.g. ({rw}, {round(cam.height * rw / cam.width)})"
            )
        if s.sensor == "micromirror_flash" and isinstance(cam, PerspectiveCfg):
            if cam.fov_deg is None and (cam.cx, cam.cy) != (cam.width / 2, cam.height / 2):
                raise ValueError(
                    "render.camera: a micromirror flash needs a centred principal point "
                    "(give fov_deg)"
                )
        return self
