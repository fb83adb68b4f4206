"""One work unit, end to end: terrain -> render -> sensor -> study (the real components).

A work unit is one resolved experiment configuration (one sweep point). It renders its scene
once and shares the image and ground truth across every strategy, density and trial of the
study. Random streams are split per stage from the experiment seed with
``SeedSequence(seed).spawn`` so that changing, say, the planner never changes the terrain, and
every sweep point of an ablation sees the same terrain and the same sampling trials (common
random numbers make the comparison sharper).

Config models become library objects (SI units, radians, option dicts and dataclasses) in
:mod:`simlunar.config.translate`; the library functions called here take arrays and
keyword-only options, never config objects.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from simlunar.config import translate
from simlunar.config.render import OrthoNadirCfg, SensorCfg, SunLightCfg
from simlunar.config.schema import ExperimentCfg
from simlunar.config.studies import SamplingStudyCfg

#: stage name -> spawn index; append only (reordering would change every result)
STAGES = ("terrain", "render", "sensor", "study", "panels")

#: bump when a change makes cached unit results invalid
#: 2: figure arrays use index coordinates (no half-cell offset)
#: 3: scanner auto-exposure from the white frame's 99.5th percentile (was 99th), exposure
#:    without a sensor model, GRAD weights around holes
CACHE_VERSION = 3


#: Renders of units running concurrently in threads (``LocalPoolExecutor``) take turns: each
#: render already uses every core, and Mitsuba scenes are built and rendered one at a time.
RENDER_LOCK = threading.RLock()


@dataclass(frozen=True, eq=False)
class UnitRecord:
    """What one work unit returns (its dict form, :meth:`to_dict`, is what executors carry
    and the unit cache stores).

    Attributes
    ----------
    rows : list of dict
        Tidy result rows (sampling: strategy, density, k, trial, metric, value).
    scores : dict
        ``{metric: {strategy: score}}`` (eq. 4.3); empty for scanner units.
    arrays : dict of str -> ndarray
        Figure arrays (image, depth, wavelet energy, plan, reconstruction, ...).
    timings : dict of str -> float
        Stage -> seconds.
    meta : dict
        Image shape, spacing, Mitsuba variant, filled ground-truth pixels.
    scans : dict or None
        Scanner units with ``study.save_scans``: the scan export payload
        (:func:`simlunar.results.exports.scan_export_payload`), which the runner writes to
        ``scans/unit<i>/`` and drops before caching; None otherwise (then absent from the dict
        form, so cached results are unchanged).
    """

    rows: list[dict[str, Any]]
    scores: dict[str, dict[str, float]]
    arrays: dict[str, np.ndarray]
    timings: dict[str, float]
    meta: dict[str, Any] = field(default_factory=dict)
    scans: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        out = {
            "rows": self.rows,
            "scores": self.scores,
            "arrays": self.arrays,
            "timings": self.timings,
            "meta": self.meta,
        }
        if self.scans is not None:
            out["scans"] = self.scans
        return out


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


# --------------------------------------------------------------------------- terrain
def build_terrain(cfg, *, rng):
    """The :class:`~simlunar.terrain.Terrain` of a :class:`TerrainCfg`
    (:func:`simlunar.config.translate.build_terrain`)."""
    return translate.build_terrain(cfg, rng=rng)


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


def luminance(image: np.ndarray) -> np.ndarray:
    """Rec. 709 luminance of a linear RGB image (rows, cols, 3) -> (rows, cols) float32."""
    image = np.asarray(image, np.float32)
    if image.ndim == 2:
        return image
    return (image[..., :3] @ np.array([0.2126, 0.7152, 0.0722], np.float32)).astype(np.float32)


def sensor_image(radiance: np.ndarray, cfg: SensorCfg | None, *, rng) -> np.ndarray:
    """Radiance (rows, cols) -> sensor image in [0, 1] (float32).

    ``exposure_e: null`` and ``sensor: null`` use the one auto-exposure rule
    (:mod:`simlunar.imaging.exposure`): the 99.5th percentile of this radiance at 80 % of the
    full well, or (no sensor) at 0.8 of the [0, 1] image, noiseless.
    """
    finite = np.nan_to_num(radiance, nan=0.0)
    if cfg is None:
        from simlunar.imaging.exposure import auto_gain

        return np.clip(finite * auto_gain(finite), 0, 1).astype(np.float32)
    from simlunar.imaging.sensor import apply_sensor

    model = translate.sensor_model(cfg, reference=finite)
    return apply_sensor(finite, model, rng=rng).astype(np.float32)


# --------------------------------------------------------------------------- study
def _panel_arrays(image, depth, energy, density: float, *, rng) -> dict:
    """Arrays for the image panels: wavelet energy, one wavelet plan and its reconstruction.

    ``energy`` is ``feature_map("wavelet", image)`` (float64), the map the plan samples from.
    """
    from simlunar.planner import plan
    from simlunar.reconstruction import reconstruct

    n = image.size
    k = max(3, round(density * n))
    p = plan("wavelet", k, weights=energy, rng=rng)
    pts = p.rc  # index coordinates: cell (r, c) sits at (r, c)
    filled = np.where(np.isfinite(depth), depth, np.nanmean(depth))
    recon = reconstruct(pts, filled[p.rows, p.cols], image.shape)
    return {
        "wavelet_energy": energy.astype(np.float32),
        "plan_rows": np.asarray(p.rows, np.int32),
        "plan_cols": np.asarray(p.cols, np.int32),
        "reconstruction": recon.astype(np.float64),
    }


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
    from scipy import ndimage

    depth = np.asarray(depth, np.float64)
    bad = ~np.isfinite(depth)
    n = int(bad.sum())
    if n == 0:
        return depth, 0
    if n == depth.size:
        raise ValueError("render: no pixel of the view sees the terrain (check the camera)")
    idx = ndimage.distance_transform_edt(bad, return_distances=False, return_indices=True)
    return depth[tuple(idx)], n


def sparse_mesh_render(
    terrain,
    camera,
    lights,
    bsdf,
    image,
    *,
    density: float,
    spp: int,
    seed: int,
    max_depth: int,
    rng,
    sigma_range: tuple[float, float] | None = None,
    threshold: float | None = None,
    energy: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Paper Fig. 4: render the terrain rebuilt from wavelet-planned samples of ``image``.

    ``density * N`` pixels are planned by wavelet energy; for the nadir orthographic camera
    pixel (r, c) is cell (r, c), so those cells' heights are Delaunay-interpolated back to the
    grid and the rebuilt terrain is rendered with the same camera, lights, BSDF and seed
    (constant roughness). With ``sigma_range`` and an Oren-Nayar ``bsdf`` it is rendered a
    second time with the paper's inferred roughness: per cell of the rebuilt DEM (= per mesh
    vertex, through the terrain UVs) the Oren-Nayar sigma is
    :func:`simlunar.render.materials.sigma_map_from_energy` of the guide image's wavelet
    energy, in ``sigma_range``; cells with normalised energy >= ``threshold`` keep the minimum
    (the planner sampled them densely, so their relief is real geometry).

    Parameters
    ----------
    terrain, camera, lights, bsdf
        The scene of the full-resolution render (nadir orthographic camera).
    image : (rows, cols) float
        Guide image (pixel (r, c) = cell (r, c)).
    density : float
        Sample fraction k / N.
    spp, seed, max_depth : int
        Render settings (the same as the full-resolution render).
    rng : numpy Generator
        Drives the wavelet plan.
    sigma_range : (float, float) or None
        ``(sigma_min, sigma_max)`` radians; None (or a non-Oren-Nayar ``bsdf``) skips the
        modulated render.
    threshold : float or None
        Normalised-energy threshold above which the geometry is kept metric.
    energy : (rows, cols) float64 or None
        ``feature_map("wavelet", image)`` when already computed (the plan samples from it).

    Returns
    -------
    dict
        ``sparse_mesh_render`` (rows, cols) float32 linear luminance (constant roughness);
        with modulation also ``sparse_mesh_render_rough`` (same, per-cell roughness) and
        ``sparse_mesh_sigma`` (rows, cols) float32 radians.
    """
    from simlunar.planner import plan
    from simlunar.reconstruction import reconstruct
    from simlunar.render import render
    from simlunar.render.materials import OrenNayarBSDF, sigma_map_from_energy
    from simlunar.terrain.types import Terrain

    if energy is None:
        from simlunar.features import feature_map

        energy = feature_map("wavelet", image)
    k = max(3, round(density * image.size))
    p = plan("wavelet", k, weights=energy, rng=rng)
    pts = p.rc  # index coordinates: cell (r, c) sits at (r, c)
    heights = np.asarray(terrain.heights, np.float64)
    recon = reconstruct(pts, heights[p.rows, p.cols], heights.shape)
    sparse = Terrain(recon, terrain.albedo, terrain.spacing, terrain.origin)
    kw = {"lights": lights, "spp": spp, "seed": seed, "max_depth": max_depth}
    bsdfs = {"sparse_mesh_render": bsdf}
    out = {}
    if sigma_range is not None and isinstance(bsdf, OrenNayarBSDF):
        lo, hi = sigma_range
        sigma = sigma_map_from_energy(energy, sigma_min=lo, sigma_max=hi, threshold=threshold)
        bsdfs["sparse_mesh_render_rough"] = OrenNayarBSDF(bsdf.sigma, bsdf.model, sigma_map=sigma)
        out["sparse_mesh_sigma"] = sigma.astype(np.float32)
    # only the renders take the lock: the plan and the reconstruction above run while another
    # unit of a parallel sweep renders
    for name, b in bsdfs.items():
        with RENDER_LOCK:
            radiance = render(sparse, camera, bsdf=b, **kw).image
        out[name] = luminance(radiance)
    return out


def compute_unit(
    payload: dict[str, Any], *, progress=None, study_workers: int = 1
) -> dict[str, Any]:
    """Run one work unit; picklable entry point for every executor.

    Parameters
    ----------
    payload : dict
        ``{"config": <plain resolved experiment dict without sweep>}``.
    progress : callable(stage, done, total), optional
        Within-unit progress of the sampling study (in-process executors pass it).
    study_workers : int
        Forked processes for the sampling study's (strategy, trial) tasks; the results do not
        depend on it.

    Returns
    -------
    dict
        :meth:`UnitRecord.to_dict`: ``rows`` (tidy dicts: strategy, density, k, trial, metric,
        value), ``scores`` ({metric: {strategy: score}}), ``arrays`` (name -> ndarray, for
        figures), ``timings`` (stage -> seconds) and ``meta``.
    """
    cfg = ExperimentCfg.model_validate(payload["config"])
    seeds = stage_seeds(cfg.seed)
    timings: dict[str, float] = {}
    t = time.perf_counter()

    terrain, camera, lights, bsdf = scene_inputs(cfg)
    timings["terrain_s"] = time.perf_counter() - t

    if not isinstance(cfg.study, SamplingStudyCfg):
        # the scanner study renders throughout (one scene per pattern sequence)
        with RENDER_LOCK:
            return _compute_scanner_unit(cfg, terrain, lights, bsdf, seeds, timings)

    t = time.perf_counter()
    from simlunar.render import render

    r = cfg.render
    with RENDER_LOCK:
        result = render(
            terrain,
            camera,
            lights=lights,
            bsdf=bsdf,
            spp=r.spp,
            seed=int_seed(seeds["render"]),
            max_depth=r.max_depth,
        )
    timings["render_s"] = time.perf_counter() - t

    t = time.perf_counter()
    radiance = luminance(result.image)
    image = sensor_image(radiance, r.sensor, rng=np.random.default_rng(seeds["sensor"]))
    depth, n_invalid = fill_invalid(np.where(result.gt.valid, result.gt.depth, np.nan))
    timings["sensor_s"] = time.perf_counter() - t

    # Figure arrays first (their seeds are their own, so the order changes no number): a
    # unit's last step is then its study, whose tasks spread over every worker, instead of a
    # render that leaves the other cores idle at the end of a parallel sweep.
    arrays = {
        "image": image,
        "radiance": radiance,
        "depth": depth,
        "heights": np.asarray(terrain.heights, np.float64),
        "albedo": np.asarray(terrain.albedo, np.float32),
    }
    if cfg.figures.enabled:
        from simlunar.features import feature_map

        panel_ss, mesh_ss = seeds["panels"].spawn(2)
        energy = feature_map("wavelet", image)  # once, for the panels and the sparse mesh
        arrays.update(
            _panel_arrays(
                image,
                depth,
                energy,
                cfg.figures.panel_density,
                rng=np.random.default_rng(panel_ss),
            )
        )
        density = cfg.figures.sparse_mesh_density
        if density is not None and isinstance(cfg.render.camera, OrthoNadirCfg):
            t = time.perf_counter()
            mesh = sparse_mesh_render(  # takes RENDER_LOCK around its renders only
                terrain,
                camera,
                lights,
                bsdf,
                image,
                density=density,
                spp=r.spp,
                seed=int_seed(seeds["render"]),
                max_depth=r.max_depth,
                rng=np.random.default_rng(mesh_ss),
                sigma_range=cfg.figures.sparse_mesh_sigma,
                threshold=cfg.figures.sparse_mesh_roughness_threshold,
                energy=energy,
            )
            arrays.update(mesh)
            timings["sparse_mesh_s"] = time.perf_counter() - t
    t = time.perf_counter()
    from simlunar.study.sampling import run_sampling_study

    s = cfg.study
    kw = {}
    used = translate.strategy_options(s)
    if used:
        kw["strategy_options"] = used
    study = run_sampling_study(
        depth,
        image,
        strategies=list(s.strategies),
        densities=list(s.densities),
        trials=s.trials,
        metrics=list(s.metrics),
        rng=np.random.default_rng(seeds["study"]),
        range_noise_std=s.range_noise_std_m,
        workers=study_workers,
        progress=None if progress is None else (lambda d, n: progress("sampling study", d, n)),
        **kw,
    )
    timings["study_s"] = time.perf_counter() - t

    return UnitRecord(
        rows=[dict(r) for r in study.rows],
        scores=_plain_scores(study.scores),
        arrays=arrays,
        timings=timings,
        meta={
            "shape": list(image.shape),
            "spacing_m": terrain.spacing,
            "variant": _variant(),
            "invalid_pixels_filled": n_invalid,
        },
    ).to_dict()


def _plain_scores(scores) -> dict:
    """Scores as {metric: {strategy: float}} whatever mapping shape the study returns."""
    out: dict[str, dict[str, float]] = {}
    for key, val in dict(scores).items():
        if isinstance(val, dict):
            for k2, v in val.items():
                out.setdefault(str(key), {})[str(k2)] = float(v)
        elif isinstance(key, tuple) and len(key) == 2:
            strategy, metric = key
            out.setdefault(str(metric), {})[str(strategy)] = float(val)
        else:
            raise ValueError(f"unexpected score entry {key!r}: {val!r}")
    return out


def _compute_scanner_unit(
    cfg: ExperimentCfg, terrain, lights, bsdf, seeds, timings
) -> dict[str, Any]:
    from simlunar.study.scanner import aim_rig_at_terrain, run_scanner_study

    s = cfg.study
    r = cfg.render
    t = time.perf_counter()
    # the scanner package aims the preset rig at the terrain's centre at the standoff that
    # fits the projection inside it, so every guide pixel sees terrain at any terrain scale
    rig = aim_rig_at_terrain(terrain, **translate.rig_kwargs(s))
    # exposure: the auto-exposure rule on the white calibration frame (RenderCapture); the
    # schema refuses a fixed exposure_e for scanner studies
    sensor = None if r.sensor is None else translate.sensor_model(r.sensor)
    sun = lights[0] if isinstance(r.light, SunLightCfg) else None
    opts = translate.scanner_options(s).kwargs()
    if s.save_scans:
        # the gray-code scan streams its frames into the decoder; the export needs the stack
        opts["gray_opts"] = {**opts["gray_opts"], "keep_frames": True}
    res = run_scanner_study(
        terrain,
        rig,
        rng=seeds["study"],
        max_depth=r.max_depth,
        spp=r.spp,
        seed=int_seed(seeds["render"]),
        sensor=sensor,
        bsdf=bsdf,
        sun=sun,
        # a daylight scan: the sun (and sky) stay on while the projector scans
        extra_lights=tuple(lights) if s.scan_light == "sun" else (),
        **opts,
    )
    timings["study_s"] = time.perf_counter() - t
    guide = res.guide
    arrays = {
        "image": np.asarray(guide.image, np.float32),
        "depth": np.where(guide.valid, guide.depth, np.nan).astype(np.float64),
    }
    scans = None
    if s.save_scans:
        # written by the runner into scans/unit<i>/ (results/exports.py)
        from simlunar.results.exports import scan_export_payload

        scans = scan_export_payload(
            res.gray, rig, gray_opts=translate.gray_kwargs(s.options.gray_opts)
        )
    return UnitRecord(
        rows=[dict(row) for row in res.rows],
        scores={},
        arrays=arrays,
        timings=timings,
        meta={"shape": list(terrain.shape), "variant": _variant()},
        scans=scans,
    ).to_dict()


def _variant() -> str:
    from simlunar.render import backend

    return backend.info().variant
