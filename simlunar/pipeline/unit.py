"""One work unit, end to end: terrain -> render -> camera model -> the study protocol.

A work unit is one resolved experiment configuration (one sweep point). It renders its scene
once and shares the image and ground truth across every planner, budget and trial of the
study. Random streams are split per stage from the experiment seed with
``SeedSequence(seed).spawn`` so that changing, say, the planner never changes the terrain, and
every sweep point of an ablation sees the same terrain and the same sampling trials (common
random numbers make the comparison sharper).

The study kind picks the unit's study and sensor (the unit functions of sampling, scanner and
lidar below, each the one protocol of :mod:`simlunar.study.protocol`, are the entries of
:data:`simlunar.pipeline.study_kinds.STUDY_UNITS`). Config models become library objects in
:mod:`simlunar.config.translate`; the library never sees a config object.
"""

from __future__ import annotations

import contextlib
import time
from typing import Any

import numpy as np
from scipy import ndimage

from simlunar.config import lidar_translate, scanner_translate, translate
from simlunar.config.render import OrthoNadirCfg, SensorCfg, SunLightCfg
from simlunar.config.scanner import ScannerStudyCfg
from simlunar.config.schema import ExperimentCfg
from simlunar.config.studies import LidarStudyCfg, SamplingStudyCfg
from simlunar.features.learned import LearnedMap, pinned_models
from simlunar.imaging.exposure import auto_gain
from simlunar.imaging.sensor import apply_sensor
from simlunar.metrics.landing import landing_hazard_maps
from simlunar.pipeline.figure_inputs import (
    RENDER_LOCK,
    RenderScene,
    panel_arrays,
    panel_energy,
    reconstruction_panel_arrays,
    sparse_mesh_render,
)
from simlunar.pipeline.guide import build_guide
from simlunar.pipeline.resume import UnitSteps
from simlunar.pipeline.study_kinds import run_study_unit, study_unit
from simlunar.pipeline.study_meta import plain_scores, reconstruction_meta, rounds_meta
from simlunar.pipeline.unit_models import read_unit_models, verify_inputs
from simlunar.progress import reporting, stage
from simlunar.reconstruction import RECONSTRUCTIONS
from simlunar.render import backend
from simlunar.render.scene import luminance
from simlunar.results.array_exports import array_export_payload, export_view
from simlunar.results.exports import scans_export_payload
from simlunar.results.lidar_exports import lidar_export_payload
from simlunar.results.records import UnitRecord
from simlunar.sensors.lidar import LidarScene
from simlunar.study.lidar import LidarStudyOptions, beam_table, run_lidar_study
from simlunar.study.reconstruction_spec import parse_reconstructions
from simlunar.study.sampling import SamplingStudyOptions, run_sampling_study
from simlunar.study.scanner import (
    ScannerScene,
    ScannerStudyOptions,
    aim_rig_at_terrain,
    run_scanner_study,
)

__all__ = [
    "CACHE_VERSION",
    "RENDER_LOCK",
    "STAGES",
    "compute_unit",
    "fill_invalid",
    "int_seed",
    "luminance",
    "scene_inputs",
    "sensor_image",
    "stage_seeds",
    "terrain_seed_sequence",
]

#: stage name -> spawn index; append only (reordering would change every result)
STAGES = ("terrain", "render", "sensor", "study", "panels", "guide")

#: bump when a change makes cached unit results invalid. 2: figure arrays use index
#: coordinates (no half-cell offset). 3: scanner auto-exposure from the white frame's 99.5th
#: percentile (was 99th), exposure without a sensor model, GRAD weights around holes.
CACHE_VERSION = 3


def stage_seeds(seed: int) -> dict[str, np.random.SeedSequence]:
    """Independent seed sequences per stage, derived from the experiment seed only."""
    children = np.random.SeedSequence(seed).spawn(len(STAGES))
    return dict(zip(STAGES, children))


def terrain_seed_sequence(seed: int, index: int = 0) -> np.random.SeedSequence:
    """Seed sequence of terrain realisation ``index`` of an experiment seed.

    Index 0 is the terrain stage's own sequence (``stage_seeds(seed)["terrain"]``, the terrain
    of every run without ``study.terrain_seeds``); index i > 0 is that sequence's child i - 1
    (``stage_seeds(seed)["terrain"].spawn(i)[i - 1]``), independent of it and of each other.
    """
    if index < 0:
        raise ValueError(f"terrain seed index must be >= 0, got {index}")
    parent = stage_seeds(seed)["terrain"]
    if index == 0:
        return parent
    return np.random.SeedSequence(parent.entropy, spawn_key=(*parent.spawn_key, index - 1))


def int_seed(ss: np.random.SeedSequence) -> int:
    """A 31-bit integer seed for code that wants an int (Mitsuba's sampler)."""
    return int(ss.generate_state(1, dtype=np.uint32)[0] & 0x7FFFFFFF)


# --------------------------------------------------------------------------- render
def scene_inputs(cfg):
    """``(terrain, camera, lights, bsdf)`` of an experiment (``ExperimentCfg``: camera, light,
    BSDF under ``render``) or of a scene (:class:`simlunar.config.scene.SceneCfg`: the same
    models at the top level).

    One function for both, so ``simlunar render`` and ``simlunar run`` give the same terrain
    for the same seed.
    """
    terrain_ss = terrain_seed_sequence(cfg.seed, cfg.terrain.seed_index)
    terrain = translate.build_terrain(cfg.terrain, rng=np.random.default_rng(terrain_ss))
    r = getattr(cfg, "render", cfg)
    return (
        terrain,
        translate.camera(r.camera, terrain),
        translate.lights(r.light, r.ambient_radiance),
        translate.bsdf(r.bsdf),
    )


def sensor_image(
    radiance: np.ndarray, cfg: SensorCfg | None, *, rng, reference: np.ndarray | None = None
) -> np.ndarray:
    """Radiance (rows, cols) -> sensor image in [0, 1] (float32).

    ``exposure_e: null`` and ``sensor: null`` use the one auto-exposure rule
    (:mod:`simlunar.imaging.exposure`): the 99.5th percentile of this radiance (or of
    ``reference``: two frames at one exposure) at 80 % of the full well, or (no sensor) at 0.8
    of the [0, 1] image, noiseless.
    """
    finite = np.nan_to_num(radiance, nan=0.0)
    ref = finite if reference is None else np.nan_to_num(reference, nan=0.0)
    if cfg is None:
        return np.clip(finite * auto_gain(ref), 0, 1).astype(np.float32)
    model = translate.sensor_model(cfg, reference=ref)
    return apply_sensor(finite, model, rng=rng).astype(np.float32)


def fill_invalid(depth: np.ndarray) -> tuple[np.ndarray, int]:
    """Fill pixels without a ground-truth hit from their nearest valid pixel.

    A nadir ray through a pixel centre passes exactly through a mesh vertex (one vertex per
    cell centre), and some such rays miss the mesh (measured: 144 of 1.6 M pixels on the full
    moonyard, about 3,450 on each full aerial scene), so the ground truth has isolated holes. The sampling study needs a finite depth everywhere; a
    hole takes its nearest neighbour's depth (the count is kept in the unit's ``meta``).

    Parameters
    ----------
    depth : (rows, cols) float
        Depth in metres, NaN where invalid.

    Returns
    -------
    filled : (rows, cols) float64
    n_invalid : int
        Number of filled pixels.
    """
    depth = np.asarray(depth, np.float64)
    bad = ~np.isfinite(depth)
    n = int(bad.sum())
    if n == 0:
        return depth, 0
    if n == depth.size:
        raise ValueError("render: no pixel of the view sees the terrain (check the camera)")
    idx = ndimage.distance_transform_edt(bad, return_distances=False, return_indices=True)
    return depth[tuple(idx)], n


def compute_unit(
    payload: dict[str, Any], *, progress=None, study_workers: int = 1
) -> dict[str, Any]:
    """Run one work unit; picklable entry point for every executor.

    Parameters
    ----------
    payload : dict
        ``{"config": <plain resolved experiment dict without sweep>, "inputs": <its input
        files' hashes, as in its cache key>}`` (:func:`simlunar.pipeline.inputs.input_hashes`;
        without ``inputs`` nothing is verified), and optionally ``"steps": {"folder", "key"}``:
        the unit's working folder, where its study keeps finished sub-steps
        (:class:`simlunar.pipeline.resume.UnitSteps`) and finds those of an interrupted run.
    progress : callable(event), optional
        Listener of the unit's progress (:func:`simlunar.progress.reporting`: stages with
        their totals, down to the frames of a scan and the beams of a LIDAR acquisition);
        in-process executors pass it.
    study_workers : int
        Forked processes for the sampling study's (strategy, trial) tasks; the results do not
        depend on it.

    Returns
    -------
    dict
        :meth:`UnitRecord.to_dict`: ``rows`` (tidy dicts), ``scores`` ({metric: {strategy:
        score}}), ``arrays`` (name -> ndarray, for figures), ``timings`` (stage -> seconds),
        ``meta`` and, for a scanner or lidar unit with ``save_scans``, ``scans``; for a
        sampling or lidar unit with ``save_arrays``, ``exports`` (its reconstructions,
        :func:`simlunar.results.array_exports.array_export_payload`).
    """
    cfg = ExperimentCfg.model_validate(payload["config"])
    inputs = payload.get("inputs")
    where = payload.get("steps")
    steps = None if not where else UnitSteps(where["folder"], where["key"])
    listening = reporting(progress) if progress is not None else contextlib.nullcontext()
    with listening:
        if not inputs:
            return _compute_unit(cfg, steps, study_workers)
        # the files the run hashed into this unit's cache key must be the ones it reads:
        # models are loaded from the verified bytes (and pinned, never read again); the other
        # files (preset, DEM, albedo) are checked before and after the unit
        models = read_unit_models(inputs, payload["config"])
        # learned maps are pinned (never read again); other models are verified before and
        # after the unit with the other files
        maps = {p: m for p, m in models.items() if isinstance(m[1], LearnedMap)}
        loaded = {k for k, v in inputs.items() if v["path"] in maps}
        loaded |= {f"{k}.json" for k in loaded}
        verify_inputs(inputs, skip=loaded)
        with pinned_models(maps):
            record = _compute_unit(cfg, steps, study_workers)
        verify_inputs(inputs, skip=loaded)
        return record


def _compute_unit(cfg, steps, study_workers: int) -> dict[str, Any]:
    seeds = stage_seeds(cfg.seed)
    timings: dict[str, float] = {}
    t = time.perf_counter()
    with stage("terrain", total=1) as s:
        terrain, camera, lights, bsdf = scene_inputs(cfg)
        s.advance()
    timings["terrain_s"] = time.perf_counter() - t
    r = cfg.render
    scene = RenderScene(
        terrain, camera, lights, bsdf, r.spp, int_seed(seeds["render"]), r.max_depth
    )
    record = run_study_unit(cfg, scene, seeds, timings, steps, workers=study_workers)
    return record.to_dict()


def _render_guide(cfg, scene: RenderScene, seeds, timings):
    """The guide view: ``(image in [0, 1], radiance, render result with its ground truth)``."""
    t = time.perf_counter()
    with RENDER_LOCK, stage("guide render", total=1, unit="frames") as s:
        result = scene.render()
        s.advance()
    timings["render_s"] = time.perf_counter() - t
    t = time.perf_counter()
    radiance = luminance(result.image)
    image = sensor_image(radiance, cfg.render.sensor, rng=np.random.default_rng(seeds["sensor"]))
    timings["sensor_s"] = time.perf_counter() - t
    return image, radiance, result


@study_unit("sampling", SamplingStudyOptions, parallel=True, config=SamplingStudyCfg)
def _sampling_unit(cfg, scene: RenderScene, seeds, timings, steps, workers) -> UnitRecord:
    """Render the guide view, then the sampling study with the ideal sensor."""
    image, radiance, result = _render_guide(cfg, scene, seeds, timings)
    t = time.perf_counter()
    depth, n_invalid = fill_invalid(np.where(result.gt.valid, result.gt.depth, np.nan))
    timings["sensor_s"] += time.perf_counter() - t
    # Figure arrays first (their seeds are their own, so the order changes no number): a
    # unit's last step is then its study, whose tasks spread over every worker, instead of a
    # render that leaves the other cores idle at the end of a parallel sweep.
    arrays = {
        "image": image,
        "radiance": radiance,
        "depth": depth,
        "heights": np.asarray(scene.terrain.heights, np.float64),
        "albedo": np.asarray(scene.terrain.albedo, np.float32),
    }
    if cfg.figures.enabled:
        with stage("figure arrays", total=1) as s:
            arrays.update(_figure_arrays(cfg, scene, image, depth, seeds, timings))
            s.advance()
    guide, guide_meta = _guide(cfg, scene, image, seeds, timings, arrays, radiance=radiance)
    options = translate.sampling_options(cfg.study)
    panel_meta: dict = {}
    if cfg.figures.enabled:
        t = time.perf_counter()
        with stage("reconstruction panels", total=1) as s:
            # its own seed (the third child of the panels' seeds), whatever runs before it
            ss = np.random.SeedSequence(
                seeds["panels"].entropy, spawn_key=(*seeds["panels"].spawn_key, 2)
            )
            panels, panel_meta = reconstruction_panel_arrays(
                options, image, depth, cfg.figures.panel_density, guide=guide, rng=ss
            )
            arrays.update(panels)
            s.advance()
        timings["recon_panels_s"] = time.perf_counter() - t
    t = time.perf_counter()
    study = run_sampling_study(
        depth,
        image,
        options,
        rng=np.random.default_rng(seeds["study"]),
        workers=workers,
        guide=guide,
        steps=steps,
        keep_trial=0 if cfg.study.save_arrays else None,
    )
    timings["study_s"] = time.perf_counter() - t
    exports = _array_exports(cfg, scene, depth, study)
    return UnitRecord(
        rows=[dict(r) for r in study.rows],
        scores=plain_scores(study.scores),
        arrays=arrays,
        timings=timings,
        meta={
            "shape": list(image.shape),
            "spacing_m": scene.terrain.spacing,
            "variant": backend.info().variant,
            "invalid_pixels_filled": n_invalid,
            **rounds_meta(study),
            **reconstruction_meta(study),
            **guide_meta,
            **panel_meta,
        },
        exports=exports,
    )


def _landing_maps(cfg, scene: RenderScene, depth, result) -> dict:
    """With ``study.landing``: the hazard maps the site choice reads (uint8, guide view) of
    the truth (``hazards_truth``) and of each planner's and reconstruction's trial-0 grid at
    the largest density (``hazards_<planner>__<reconstruction>``), for the hazard-map figure."""
    opts = lidar_translate.landing_options(cfg.study.landing)
    if opts is None:
        return {}
    truth = scene.camera.unproject_depth(depth)
    out = {"hazards_truth": landing_hazard_maps(truth, truth, opts).astype(np.uint8)}
    top = int(np.argmax(result.densities)) if result.densities else 0
    for (label, d, recon), grid in result.grids.items():
        if d == top:
            pts = scene.camera.unproject_depth(np.asarray(grid, float))
            out[f"hazards_{label}__{recon}"] = landing_hazard_maps(pts, truth, opts).astype(
                np.uint8
            )
    return out


def _array_exports(cfg, scene: RenderScene, depth, result) -> dict | None:
    """The ``arrays/unit<i>/`` payload of a sampling or lidar study's ``result`` (its grids,
    densities and ks) when ``study.save_arrays`` is set (written by the runner); else None."""
    if not cfg.study.save_arrays:
        return None
    view = export_view(scene.camera, scene.terrain, depth.shape)
    return array_export_payload(
        result.grids, depth, densities=result.densities, ks=result.ks, view=view
    )


def _guide(cfg, scene: RenderScene, image, seeds, timings, arrays: dict, radiance=None):
    """The guided reconstructions' :class:`~simlunar.reconstruction.Guide` (the guide view's
    image and the extra frames of ``render.guide_frames``, :mod:`simlunar.pipeline.guide`)
    and the unit meta naming its frames; ``(None, {})`` when no configured reconstruction reads
    the image (no extra frame is rendered then: nothing would read it)."""
    specs = parse_reconstructions(cfg.study.reconstructions)
    if not any(RECONSTRUCTIONS[s.name].meta.get("guided") for s in specs):
        return None, {}

    def develop(rad, rng, reference=None):
        return sensor_image(rad, cfg.render.sensor, rng=rng, reference=reference)

    with stage("guide frames", total=1) as s:
        guide, frames = build_guide(
            cfg, scene, image, seeds["guide"], develop=develop, lock=RENDER_LOCK,
            timings=timings, radiance=radiance,
        )  # fmt: skip
        s.advance()
    arrays.update({f"guide_{name}": img for name, img in frames.items()})
    return guide, {"guide_frames": list(guide.frames)}


def _figure_arrays(cfg, scene: RenderScene, image, depth, seeds, timings) -> dict:
    """The image panels' arrays and, for a nadir view, the sparse-mesh renders (Fig. 4)."""
    panel_ss, mesh_ss = seeds["panels"].spawn(2)
    energy = panel_energy(image)  # once, for the panels and the sparse mesh
    f = cfg.figures
    out = panel_arrays(image, depth, energy, f.panel_density, rng=np.random.default_rng(panel_ss))
    if f.sparse_mesh_density is not None and isinstance(cfg.render.camera, OrthoNadirCfg):
        t = time.perf_counter()
        out.update(
            sparse_mesh_render(  # takes RENDER_LOCK around its renders only
                scene,
                image,
                density=f.sparse_mesh_density,
                rng=np.random.default_rng(mesh_ss),
                sigma_range=f.sparse_mesh_sigma,
                threshold=f.sparse_mesh_roughness_threshold,
                energy=energy,
            )
        )
        timings["sparse_mesh_s"] = time.perf_counter() - t
    return out


@study_unit("scanner", ScannerStudyOptions, renders=True, config=ScannerStudyCfg)
def _scanner_unit(cfg, scene: RenderScene, seeds, timings, steps) -> UnitRecord:
    """The scanner study with the structured-light sensor on a rig aimed at the terrain."""
    s, r = cfg.study, cfg.render
    t = time.perf_counter()
    # the scanner package aims the preset rig at the terrain's centre at the standoff that
    # fits the projection inside it, so every guide pixel sees terrain at any terrain scale
    rig = aim_rig_at_terrain(scene.terrain, **scanner_translate.rig_kwargs(s))
    # exposure: the auto-exposure rule on the white calibration frame (RenderCapture); the
    # schema refuses a fixed exposure_e for scanner studies
    study_scene = ScannerScene(
        scene.terrain,
        rig,
        bsdf=scene.bsdf,
        camera_model=None if r.sensor is None else translate.sensor_model(r.sensor),
        sun=scene.lights[0] if isinstance(r.light, SunLightCfg) else None,
        # a daylight scan: the sun (and sky) stay on while the projector scans
        extra_lights=tuple(scene.lights) if s.scan_light == "sun" else (),
    )
    options = scanner_translate.scanner_options(s, r, seed=scene.seed)
    res = run_scanner_study(study_scene, options, rng=seeds["study"], steps=steps)
    timings["study_s"] = time.perf_counter() - t
    guide = res.guide
    arrays = {
        "image": np.asarray(guide.image, np.float32),
        "depth": np.where(guide.valid, guide.depth, np.nan).astype(np.float64),
    }
    # written by the runner into scans/unit<i>/<coding>/ (results/exports.py)
    scans = scans_export_payload(res.coded, rig) if s.save_scans else None
    return UnitRecord(
        rows=[dict(row) for row in res.rows],
        scores={},
        arrays=arrays,
        timings=timings,
        meta={"shape": list(scene.terrain.shape), "variant": backend.info().variant},
        scans=scans,
    )


@study_unit("lidar", LidarStudyOptions, config=LidarStudyCfg)
def _lidar_unit(cfg, scene: RenderScene, seeds, timings, steps) -> UnitRecord:
    """Render the guide view, then the LIDAR study with the sensor at the guide camera (the
    sun of a sun-lit scene is the LIDAR's background)."""
    image, radiance, result = _render_guide(cfg, scene, seeds, timings)
    depth = np.where(result.gt.valid, result.gt.depth, np.nan).astype(np.float64)
    arrays: dict = {}
    guide, guide_meta = _guide(cfg, scene, image, seeds, timings, arrays, radiance=radiance)
    sun = scene.lights[0] if isinstance(cfg.render.light, SunLightCfg) else None
    lidar_scene = LidarScene(scene.terrain, scene.camera, bsdf=scene.bsdf, sun=sun)
    t = time.perf_counter()
    with RENDER_LOCK:  # the sensor renders every acquisition
        res = run_lidar_study(
            lidar_scene,
            (image, depth),
            lidar_translate.lidar_options(cfg.study, seed=scene.seed),
            rng=np.random.default_rng(seeds["study"]),
            reconstruction_guide=guide,
            steps=steps,
            keep_trial=0 if cfg.study.save_arrays or cfg.study.landing is not None else None,
        )
    timings["study_s"] = time.perf_counter() - t
    arrays = {"image": image, "depth": depth, **arrays, **_landing_maps(cfg, scene, depth, res)}
    for label, acq in res.examples.items():
        # where the example acquisition measured, and what: (row, col, depth) per sample
        arrays[f"samples_{label}"] = np.c_[acq.rc, acq.values].astype(np.float64)
        # every beam in visiting order: (row, col, time, depth), for the scan figure
        arrays[f"beams_{label}"] = beam_table(acq)
    scans = None
    if cfg.study.save_scans:  # written by the runner into scans/unit<i>/
        scans = lidar_export_payload(res.examples, scene.camera, image.shape[:2], scene.terrain.crs)
    exports = _array_exports(cfg, scene, depth, res)
    return UnitRecord(
        rows=[dict(row) for row in res.rows],
        scores={},
        arrays=arrays,
        timings=timings,
        meta={
            "shape": list(image.shape),
            "sensor": cfg.study.sensor,
            "variant": backend.info().variant,
            **guide_meta,
        },
        scans=scans,
        exports=exports,
    )
