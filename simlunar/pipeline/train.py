"""``simlunar train``: render training examples from a training YAML and fit the learned map
or the learned reconstruction's residual model (the YAML's ``target``).

Each example is the guide view and true depth of one (experiment scene, preset, terrain
realisation, sun elevation), rendered exactly as a sampling unit renders it (same terrain,
camera, light, BSDF, sensor; :mod:`simlunar.pipeline.unit`), with the training YAML's ``seed``
(terrains no study of the experiments sees). The model file and its JSON record are results:
the record holds the training config, the presets / seeds / sun angles, the experiments' seeds,
the hashes of every training input, the command line and the library versions.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from simlunar.config.loading import to_plain
from simlunar.config.training import LearnedReconCfg, TrainCfg, _preset, _sweep_presets
from simlunar.config.yamlio import dump_yaml
from simlunar.features.learned import LearnedOptions
from simlunar.pipeline.figure_inputs import RENDER_LOCK, RenderScene
from simlunar.pipeline.guide import build_guide
from simlunar.pipeline.preflight import check_out_file
from simlunar.pipeline.unit import fill_invalid, int_seed, scene_inputs, sensor_image, stage_seeds
from simlunar.planner.learning import train_learned_map, train_learned_reconstruction
from simlunar.progress import Event, reporting
from simlunar.reconstruction import RECONSTRUCTIONS
from simlunar.render.scene import luminance

__all__ = ["guide_view", "train_from_config"]


def guide_view(cfg, *, with_guide: bool = False):
    """``(image float32, depth float64)`` of an experiment config's scene, as its unit renders
    them (the same seeds per stage); with ``with_guide``, ``(image, depth, guide)``: the
    :class:`~simlunar.reconstruction.Guide` its guided reconstructions read (the frames of
    ``render.guide_frames`` rendered as the unit renders them,
    :func:`simlunar.pipeline.guide.build_guide`)."""
    seeds = stage_seeds(cfg.seed)
    terrain, camera, lights, bsdf = scene_inputs(cfg)
    r = cfg.render
    scene = RenderScene(terrain, camera, lights, bsdf, r.spp, int_seed(seeds["render"]),
                        r.max_depth)  # fmt: skip
    with RENDER_LOCK:
        res = scene.render()
    image = sensor_image(luminance(res.image), r.sensor, rng=np.random.default_rng(seeds["sensor"]))
    depth, _ = fill_invalid(np.where(res.gt.valid, res.gt.depth, np.nan))
    if not with_guide:
        return image, depth

    def develop(radiance, rng):
        return sensor_image(radiance, r.sensor, rng=rng)

    guide, _ = build_guide(cfg, scene, image, seeds["guide"], develop=develop, lock=RENDER_LOCK)
    return image, depth, guide


def _scenes(cfg: TrainCfg, experiments) -> list[tuple[dict, object]]:
    """(description, experiment config) of every training example."""
    out = []
    for exp in experiments:
        for value in _sweep_presets(exp):
            preset = _preset(exp, value)
            if preset in cfg.held_out_presets:
                continue
            suns = cfg.sun_elevations_deg or [getattr(exp.render.light, "elevation_deg", None)]
            for seed_index in range(cfg.terrain_seeds):
                for sun in suns:
                    terrain = exp.terrain.model_copy(
                        update={"preset": preset, "scale": cfg.scale, "seed_index": seed_index}
                    )
                    update = {"terrain": terrain, "seed": cfg.seed, "sweep": {}}
                    if sun is not None and hasattr(exp.render.light, "elevation_deg"):
                        light = exp.render.light.model_copy(update={"elevation_deg": sun})
                        update["render"] = exp.render.model_copy(update={"light": light})
                    what = {"experiment": exp.name, "preset": preset, "seed": cfg.seed,
                            "seed_index": seed_index, "sun_elevation_deg": sun}  # fmt: skip
                    out.append((what, exp.model_copy(update=update)))
    return out


def train_from_config(cfg: TrainCfg, experiments, *, out: str | Path | None = None,
                      command: str = "", log=print) -> tuple[Path, Path]:  # fmt: skip
    """Render the examples, train the ``cfg.target`` (map or reconstruction), save ``model``
    (``out`` overrides it) and its record.

    Returns
    -------
    (Path, Path)
        The ``.joblib`` model and its ``.json`` record.
    """
    path = Path(out) if out is not None else Path(cfg.model)
    # the model and its record must be writable before minutes of rendering and training
    option = "--out" if out is not None else "model"
    check_out_file(path, option=option)
    check_out_file(path.with_suffix(".json"), option=option)
    t0 = time.perf_counter()
    examples, described, guides = [], [], []
    error_name, _ = cfg.error_reconstruction_spec()
    with_guide = bool(RECONSTRUCTIONS[error_name].meta.get("guided"))
    scenes = _scenes(cfg, experiments)
    for what, exp in scenes:
        view = guide_view(exp, with_guide=True) if with_guide else guide_view(exp)
        examples.append(view[:2])
        guides.append(view[2] if with_guide else None)
        described.append(what)
        log(f"rendered {len(examples)}/{len(scenes)}: {what['preset']} seed_index "
            f"{what['seed_index']} sun {what['sun_elevation_deg']}")  # fmt: skip
    render_s = time.perf_counter() - t0
    provenance = {
        "name": cfg.name,
        "description": cfg.description,
        "command": command,
        "training_config": cfg.recorded(),
        "training_yaml": dump_yaml(cfg.recorded()),
        "examples": described,
        "held_out_presets": list(cfg.held_out_presets),
        "experiments": [
            {"name": e.name, "seed": e.seed, "config": to_plain(e)} for e in experiments
        ],
        "render_seconds": round(render_s, 3),
    }
    options = LearnedOptions(**cfg.options.model_dump())
    target = "reconstruction" if cfg.target == "reconstruction" else "map"
    log(f"fitting the learned {target} on {len(examples)} examples "
        f"({len(cfg.densities)} densities)")  # fmt: skip
    t1 = time.perf_counter()
    with reporting(_StageLines(log)):
        model = _fit(cfg, examples, options, provenance, guides)
    log(f"fitted in {time.perf_counter() - t1:.1f} s")
    path = Path(out) if out is not None else Path(cfg.model)
    return model.save(path)


class _StageLines:
    """The fitting's stages (:mod:`simlunar.progress`) as log lines: each stage's progress at
    most once per ``every_s``, and when it reaches its total."""

    def __init__(self, log, *, every_s: float = 10.0):
        self.log, self.every_s = log, every_s
        self.last = time.monotonic()

    def __call__(self, ev: Event) -> None:
        now = time.monotonic()
        complete = ev.total is not None and ev.done == ev.total
        if ev.finished or ev.done == 0 or not (complete or now - self.last >= self.every_s):
            return
        self.last = now
        self.log(ev.text())


def _fit(cfg: TrainCfg, examples, options: LearnedOptions, provenance: dict, guides: list):
    """The model of ``cfg.target`` fitted to the rendered examples (``guides``: each
    example's guide, for a map learned on a guided reconstruction's error)."""
    if cfg.target == "reconstruction":
        recon = cfg.reconstruction or LearnedReconCfg()
        return train_learned_reconstruction(
            examples,
            densities=cfg.densities,
            options=options,
            with_shading=recon.with_shading,
            shading_options=recon.shading_options,
            rng=np.random.default_rng(np.random.SeedSequence([cfg.seed, 21])),
            provenance=provenance,
        )
    target = {}
    if cfg.error_reconstruction != "linear":  # the call (and the model) of before
        error_name, error_options = cfg.error_reconstruction_spec()
        with_guide = bool(RECONSTRUCTIONS[error_name].meta.get("guided"))
        target = {"error_reconstruction": error_name,
                  "reconstruction_options": error_options,
                  "guides": guides if with_guide else None}  # fmt: skip
    return train_learned_map(
        examples,
        densities=cfg.densities,
        options=options,
        rng=np.random.default_rng(np.random.SeedSequence([cfg.seed, 20])),
        provenance=provenance,
        **target,
    )
