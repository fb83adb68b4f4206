"""Scene description files for ``simlunar render SCENE.yaml --out DIR``.

A scene YAML says what to render: ``terrain``, ``camera``, ``light``, ``bsdf``, ``spp``,
``max_depth``, ``seed`` and an optional ``sensor``, with the experiment schema's own models
(:mod:`simlunar.config.schema`: a scene is an experiment's ``terrain`` and ``render``
sections, flattened). Keys carry unit suffixes (``_deg``, ``_m``); unknown keys are errors.

The same ``seed`` gives the same terrain as an experiment with that seed (the per-stage seed
split of :func:`simlunar.pipeline.unit.stage_seeds`).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from pydantic import Field, ValidationError

from simlunar.atomic import atomic_write
from simlunar.config import translate
from simlunar.config.fields import _Model
from simlunar.config.loading import format_validation_error, load_yaml
from simlunar.config.render import (
    BsdfCfg,
    CameraCfg,
    LightCfg,
    OrenNayarCfg,
    OrthoNadirCfg,
    SensorCfg,
    SunLightCfg,
)
from simlunar.config.terrain import TerrainCfg
from simlunar.errors import ConfigError


class SceneCfg(_Model):
    """One rendered view: terrain, camera, light, BSDF and sampling."""

    name: str = Field("scene", pattern=r"^[A-Za-z0-9_.-]+$")
    description: str = ""
    terrain: TerrainCfg
    camera: CameraCfg = Field(default_factory=OrthoNadirCfg)
    light: LightCfg = Field(default_factory=SunLightCfg)
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
    data = load_yaml(path)
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: <root>: expected a mapping of keys, got {type(data).__name__}")
    try:
        cfg = SceneCfg.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(f"{path}: {format_validation_error(exc, data)}") from None
    from simlunar.config.loading import resolve_terrain_files

    return resolve_terrain_files(cfg, path.parent)


def build_camera(cfg, terrain):
    """Geometry camera of a camera config (:func:`simlunar.config.translate.camera`)."""
    return translate.camera(cfg, terrain)


def build_lights(cfg: SceneCfg) -> list:
    """Light specs of a scene config (the light, plus the ambient term when > 0)."""
    return translate.lights(cfg.light, cfg.ambient_radiance)


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
    from simlunar.pipeline.unit import int_seed, scene_inputs, stage_seeds

    terrain, camera, lights, bsdf = scene_inputs(cfg)  # as an experiment's unit builds them
    t1 = time.perf_counter()
    render_seed = int_seed(stage_seeds(cfg.seed)["render"])
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
        from simlunar.pipeline.unit import luminance, sensor_image, stage_seeds

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
