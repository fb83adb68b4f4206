"""Scene description files for ``simlunar render SCENE.yaml --out DIR``.

A scene YAML says what to render: ``terrain`` (the experiment schema's
:class:`~simlunar.pipeline.config.TerrainCfg`: a preset or a DEM file), ``camera``,
``light``, ``bsdf`` (the experiment schema's BSDF models), ``spp``, ``max_depth``, ``seed`` and
an optional ``sensor``. Keys carry unit suffixes (``_deg``, ``_m``); unknown keys are errors.
The camera and light models here are supersets of the experiment schema's (perspective
cameras from ``fx/fy/cx/cy`` or thin lens; the finite solar disk; an ambient term), so the
experiment schema can adopt them unchanged.

The same ``seed`` gives the same terrain as an experiment with that seed (the per-stage seed
split of :func:`simlunar.pipeline.stages.stage_seeds`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Literal

import numpy as np
import yaml
from pydantic import Field, ValidationError, model_validator

from simlunar.atomic import atomic_write
from simlunar.errors import ConfigError
from simlunar.pipeline.config import (
    BsdfCfg,
    CameraLightCfg,
    Deg,
    Metres,
    OrenNayarCfg,
    OrthoNadirCfg,
    SensorCfg,
    SunLightCfg,
    TerrainCfg,
    _Model,
    format_validation_error,
)
from simlunar.pipeline.schema import _tagged_union

Vec3 = tuple[float, float, float]


class PerspectiveSceneCfg(_Model):
    """Pinhole (or thin-lens) camera at ``position_m`` looking at ``look_at_m``.

    Give either ``fov_deg`` (horizontal; square pixels, centred principal point) or all of
    ``fx, fy, cx, cy`` (pixels; pixel centres at i + 0.5, so centred is ``width/2``).
    """

    kind: Literal["perspective"]
    width: int = Field(gt=0, le=16384)
    height: int = Field(gt=0, le=16384)
    fov_deg: Deg | None = Field(None, gt=0, lt=180, description="horizontal field of view")
    fx: float | None = Field(None, gt=0)
    fy: float | None = Field(None, gt=0)
    cx: float | None = None
    cy: float | None = None
    position_m: Vec3
    look_at_m: Vec3
    up: Vec3 = (0.0, 0.0, 1.0)
    aperture_radius_m: Metres = Field(0.0, ge=0, description="thin lens; 0 = pinhole")
    focus_distance_m: Metres | None = Field(None, gt=0)

    @model_validator(mode="after")
    def _intrinsics(self) -> PerspectiveSceneCfg:
        k = [self.fx, self.fy, self.cx, self.cy]
        if self.fov_deg is None and any(v is None for v in k):
            raise ValueError("give fov_deg or all of fx, fy, cx, cy")
        if self.fov_deg is not None and any(v is not None for v in k):
            raise ValueError("give fov_deg or fx, fy, cx, cy, not both")
        if self.aperture_radius_m > 0 and self.focus_distance_m is None:
            raise ValueError("a thin lens (aperture_radius_m > 0) needs focus_distance_m")
        return self


class SunSceneCfg(SunLightCfg):
    """Distant sun; ``angular_diameter_deg`` 0.53 gives the real solar disk (soft shadows)."""

    angular_diameter_deg: Deg = Field(0.0, ge=0, lt=90)

    @property
    def angular_diameter(self) -> float:
        return math.radians(self.angular_diameter_deg)


SceneCameraCfg = _tagged_union("orthographic_nadir", OrthoNadirCfg, PerspectiveSceneCfg)
SceneLightCfg = _tagged_union("sun", SunSceneCfg, CameraLightCfg)


class SceneCfg(_Model):
    """One rendered view: terrain, camera, light, BSDF and sampling."""

    name: str = Field("scene", pattern=r"^[A-Za-z0-9_.-]+$")
    description: str = ""
    terrain: TerrainCfg
    camera: SceneCameraCfg = Field(default_factory=OrthoNadirCfg)
    light: SceneLightCfg = Field(default_factory=SunSceneCfg)
    ambient_radiance: float = Field(0.0, ge=0, description="constant sky radiance (0 = off)")
    bsdf: BsdfCfg = Field(default_factory=lambda: OrenNayarCfg(kind="oren_nayar"))
    spp: int = Field(16, ge=1, le=65536)
    max_depth: int = Field(3, ge=2, le=64, description="path depth (2 = direct light only)")
    seed: int = Field(0, ge=0, lt=2**31)
    sensor: SensorCfg | None = Field(None, description="also write a noisy sensor image")


def load_scene(path) -> SceneCfg:
    """Read and validate a scene YAML; DEM paths are taken relative to the YAML's folder.

    Raises
    ------
    FileNotFoundError
        The YAML (or a DEM / albedo file it names) does not exist.
    ConfigError
        Invalid YAML or an invalid key (the message names the key path).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"scene file not found: {path}")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML ({exc})") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping of keys, got {type(data).__name__}")
    try:
        cfg = SceneCfg.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(f"{path}: {format_validation_error(exc, data)}") from None
    from simlunar.pipeline.config import resolve_terrain_files

    return resolve_terrain_files(cfg, path.parent)


def _seeds(seed: int) -> tuple[np.random.SeedSequence, int]:
    from simlunar.pipeline.stages import stage_seeds

    s = stage_seeds(seed)
    render_seed = int(s["render"].generate_state(1, dtype=np.uint32)[0] & 0x7FFFFFFF)
    return s["terrain"], render_seed


def build_camera(cfg, terrain):
    """geometry camera of a camera config (orthographic nadir over ``terrain`` or perspective)."""
    from simlunar.geometry import Camera, Intrinsics, OrthoCamera, Pose

    if isinstance(cfg, OrthoNadirCfg):
        return OrthoCamera.nadir_for_grid(
            terrain.shape, terrain.spacing, terrain.origin, altitude=cfg.altitude_m
        )
    if cfg.fov_deg is not None:
        k = Intrinsics.from_fov(cfg.width, cfg.height, cfg.fov_deg)
    else:
        k = Intrinsics(cfg.fx, cfg.fy, cfg.cx, cfg.cy, cfg.width, cfg.height)
    return Camera(
        k,
        Pose.look_at(cfg.position_m, cfg.look_at_m, cfg.up),
        aperture_radius=cfg.aperture_radius_m,
        focus_distance=cfg.focus_distance_m,
    )


def build_lights(cfg: SceneCfg) -> list:
    """Light specs of a scene config (the light, plus the ambient term when > 0)."""
    from simlunar.render.lights import make_light

    light = cfg.light
    if isinstance(light, SunSceneCfg):
        out = [
            make_light(
                "sun",
                elevation=light.elevation,
                azimuth=light.azimuth,
                irradiance=light.irradiance,
                angular_diameter=light.angular_diameter,
            )
        ]
    else:
        out = [make_light("camera", intensity=light.intensity)]
    if cfg.ambient_radiance > 0:
        out.append(make_light("ambient", radiance=cfg.ambient_radiance))
    return out


def build_scene_inputs(cfg: SceneCfg):
    """``(terrain, camera, lights, bsdf)`` for :func:`simlunar.render.render`."""
    from simlunar.pipeline.stages import build_bsdf, build_terrain, terrain_seed_sequence

    terrain_ss = terrain_seed_sequence(cfg.seed, cfg.terrain.seed_index)
    terrain = build_terrain(cfg.terrain, rng=np.random.default_rng(terrain_ss))
    return terrain, build_camera(cfg.camera, terrain), build_lights(cfg), build_bsdf(cfg.bsdf)


def render_scene(cfg: SceneCfg, out_dir) -> dict[str, Path]:
    """Render a scene and write its outputs to ``out_dir`` (created), each file atomically.

    Files: ``radiance.exr`` (linear RGB float32), ``preview.png`` (sRGB, auto exposure),
    ``ground_truth.exr`` (float32 channels ``depth``, ``position.X/Y/Z``, ``normal.X/Y/Z``,
    ``valid``), ``ground_truth.npz`` (the same in float64 / bool), ``scene.json`` (resolved
    config and timings) and, with a ``sensor``, ``sensor.png`` (the noisy 8-bit-quantised
    sensor image).

    Returns
    -------
    dict
        Output name -> path.
    """
    import time

    from simlunar.imaging.exr import write_exr
    from simlunar.imaging.png import write_png_preview
    from simlunar.render import render

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    terrain, camera, lights, bsdf = build_scene_inputs(cfg)
    t1 = time.perf_counter()
    _, render_seed = _seeds(cfg.seed)
    res = render(
        terrain,
        camera,
        lights=lights,
        bsdf=bsdf,
        spp=cfg.spp,
        seed=render_seed,
        max_depth=cfg.max_depth,
    )
    t2 = time.perf_counter()
    gt = res.gt
    attrs = {"scene": cfg.name, "spp": cfg.spp, "seed": cfg.seed}
    paths = {
        "radiance": write_exr(out / "radiance.exr", res.image, attrs=attrs),
        "preview": write_png_preview(out / "preview.png", res.image),
    }
    channels = {"depth": gt.depth, "valid": gt.valid.astype(np.float32)}
    for i, ax in enumerate("XYZ"):
        channels[f"position.{ax}"] = gt.position[..., i]
        channels[f"normal.{ax}"] = gt.normal[..., i]
    paths["ground_truth"] = write_exr(out / "ground_truth.exr", channels, attrs=attrs)
    paths["ground_truth_npz"] = _write_npz(
        out / "ground_truth.npz",
        depth=gt.depth,
        position=gt.position,
        normal=gt.normal,
        valid=gt.valid,
    )
    if cfg.sensor is not None:
        from simlunar.pipeline.stages import luminance, sensor_image, stage_seeds

        rng = np.random.default_rng(stage_seeds(cfg.seed)["sensor"])
        img = sensor_image(luminance(res.image), cfg.sensor, rng=rng)
        paths["sensor"] = write_png_preview(out / "sensor.png", img, exposure=1.0)
    meta = {
        "config": cfg.model_dump(mode="json"),
        "terrain_s": round(t1 - t0, 3),
        "render_s": round(t2 - t1, 3),
        "shape": list(res.image.shape[:2]),
    }
    paths["scene"] = _write_text(out / "scene.json", json.dumps(meta, indent=1))
    return paths


def _write_npz(path: Path, **arrays) -> Path:
    return atomic_write(path, lambda tmp: np.savez_compressed(tmp, **arrays))


def _write_text(path: Path, text: str) -> Path:
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text))
