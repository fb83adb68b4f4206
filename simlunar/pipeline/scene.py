"""``simlunar render SCENE.yaml``: render one scene and write its files (radiance, preview,
ground truth, optional sensor image, ``scene.json``).

The terrain, camera, lights and BSDF are built by :func:`simlunar.pipeline.unit.scene_inputs`, as
an experiment's unit builds them: the same ``seed`` gives the same terrain in both.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from simlunar.atomic import atomic_write
from simlunar.config.scene import SceneCfg
from simlunar.errors import ResultFolderError
from simlunar.imaging.exr import write_exr
from simlunar.imaging.png import write_png_preview
from simlunar.pipeline.unit import int_seed, luminance, scene_inputs, sensor_image, stage_seeds
from simlunar.render import render

__all__ = ["check_render_folder", "render_scene"]

#: the file that marks a folder as written by ``simlunar render``
RENDER_MARK = "scene.json"


def check_render_folder(out_dir) -> None:
    """Refuse (:class:`ResultFolderError`) a non-empty ``out_dir`` that is not a render
    folder (no ``scene.json``), as ``simlunar run`` refuses a folder that is not its own:
    rendering into an experiment's result folder, or any other, would mix files."""
    out = Path(out_dir)
    if not out.is_dir() or (out / RENDER_MARK).is_file():
        return
    others = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    if others:
        what = (
            "an experiment's result folder"
            if (out / "config.yaml").is_file()
            else f"not a render folder (no {RENDER_MARK}, found {others[0]})"
        )
        raise ResultFolderError(f"--out {out}: not empty and {what}; choose an empty or new folder")


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
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    terrain, camera, lights, bsdf = scene_inputs(cfg)  # as an experiment's unit builds them
    t1 = time.perf_counter()
    render_seed = int_seed(stage_seeds(cfg.seed)["render"])
    res = render(
        terrain,
        camera,
        lights=lights,
        bsdf=bsdf,
        spp=cfg.render.spp,
        seed=render_seed,
        max_depth=cfg.render.max_depth,
    )
    t2 = time.perf_counter()
    gt = res.gt
    attrs = {"scene": cfg.name, "spp": cfg.render.spp, "seed": cfg.seed}
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
    if cfg.render.sensor is not None:
        rng = np.random.default_rng(stage_seeds(cfg.seed)["sensor"])
        img = sensor_image(luminance(res.image), cfg.render.sensor, rng=rng)
        paths["sensor"] = write_png_preview(out / "sensor.png", img, exposure=1.0)
    meta = {
        "config": cfg.model_dump(mode="json"),
        "terrain_s": round(t1 - t0, 3),
        "render_s": round(t2 - t1, 3),
        "shape": list(res.image.shape[:2]),
    }
    paths["scene"] = _write_text(out / RENDER_MARK, json.dumps(meta, indent=1))
    return paths


def _write_npz(path: Path, **arrays) -> Path:
    return atomic_write(path, lambda tmp: np.savez_compressed(tmp, **arrays))


def _write_text(path: Path, text: str) -> Path:
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text))
