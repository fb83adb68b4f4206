"""Sparse frames at DLP size: the lit-pixel light tracer against Mitsuba's ptracer.

``sparse_frame``: the rig of ``experiments/scanner_ambiguity_dlp.yaml`` (the full moonyard,
1024 x 768 projector, 2048 x 1536 camera of 60 deg field of view, Oren-Nayar 20 deg, max_depth
3) in one process. Timed, each after a warm-up render (kernels compiled or loaded once):

- ``full_s``: one half-lit frame (64 px stripes) path traced at the experiment's spp (8);
- ``ptracer_dot_s``: one frame of ``DOTS`` random one-pixel dots light traced by Mitsuba's
  ``ptracer`` at spp 1 (the experiment's ``sparse_integrator: ptracer, sparse_spp: 1``);
- ``lit_dot_s``: the same frame by :class:`simlunar.render.sparse.LitTracer` at
  ``sparse_particles`` (256) paths per dot, one frame per launch; ``lit_batch_dot_s`` per frame
  of ``BATCH`` dot frames in one launch (``dot_scan`` renders 8 frames per call).

``dot_over_full`` = ``lit_dot_s / full_s`` (goal <= 0.05), beside ``ptracer_dot_over_full`` and
``dot_over_full_batched``. ``reference_s`` / ``ours_s`` = ptracer / lit dot frame (the printed
ratio is the speed-up). Agreement on the timed frame: the total (``energy_ratio``, lit over
ptracer) and the dots found by :func:`simlunar.scanner.dots.detect_dots` with ``dot_scan``'s
thresholds on the exposed frames (lens PSF 1 px, exposure of the half-lit frame, no sensor
noise): counts, the fraction matched within 0.5 camera px and their median distance.
"""

from __future__ import annotations

import os
import time

import numpy as np

#: DLP rig of experiments/scanner_ambiguity_dlp.yaml
PROJ, CAM, SPP, MAX_DEPTH = (1024, 768), (2048, 1536), 8, 3
DOTS, BATCH, PARTICLES = 1000, 8, 256
#: ``smoke=True``: projector, camera, dots, batch, particles, moonyard scale (same code paths)
SMOKE = {"proj": (64, 48), "cam": (64, 48), "dots": 20, "batch": 2, "particles": 16, "scale": 0.08}


def _scene(proj=PROJ, cam=CAM, scale=1.0, spp=SPP):
    from simlunar.config.translate import preset_params
    from simlunar.render.lights import ProjectorLight
    from simlunar.render.materials import OrenNayarBSDF
    from simlunar.render.scene import TerrainScene
    from simlunar.study import scanner as st
    from simlunar.terrain import generate

    # the full 971 x 1674 moonyard (scale 1)
    terr = generate(preset_params("moonyard"), rng=0, scale=scale).terrain
    rig = st.aim_rig_at_terrain(terr, proj_size=proj, cam_size=cam, cam_fov_x=np.radians(60.0))
    light = ProjectorLight(rig.projector, np.ones(proj[::-1], np.float32))
    bsdf = OrenNayarBSDF(np.radians(20.0))
    return TerrainScene(
        terr, rig.camera, lights=[light], bsdf=bsdf, max_depth=MAX_DEPTH, spp=spp, seed=0
    )


def _dot_frames(n: int, rng, proj=PROJ, n_dots=DOTS) -> np.ndarray:
    from simlunar.scanner import dots

    W, H = proj
    out = []
    for _ in range(n):
        flat = rng.choice(W * H, size=n_dots, replace=False)
        out.append(dots.dot_pattern((H, W), np.c_[flat % W + 0.5, flat // W + 0.5]))
    return np.stack(out)


def _timed(fn, reps: int) -> tuple[float, np.ndarray]:
    """Median wall time of ``reps`` calls after one warm-up call; the last result."""
    out = fn()
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def _detections(frame: np.ndarray, gain: float):
    from simlunar.imaging.blur import gaussian_blur
    from simlunar.scanner import dots

    img = gaussian_blur(np.ascontiguousarray(frame, np.float32), 1.0) * np.float32(gain)
    return dots.detect_dots(img, background=0.0, rel_threshold=0.02, abs_threshold=0.02)


def bench_sparse_frame(*, smoke: bool = False) -> dict:
    """The sparse-frame figures of the module docstring (``smoke``: a 64 x 48 rig, 20 dots)."""
    from scipy.spatial import cKDTree

    from simlunar.render.sparse import LitTracer

    if smoke:
        proj, cam, n_dots = SMOKE["proj"], SMOKE["cam"], SMOKE["dots"]
        batch, particles, spp, reps = SMOKE["batch"], SMOKE["particles"], 1, 1
        scene = _scene(proj, cam, SMOKE["scale"], spp)
    else:
        proj, n_dots, batch, particles, spp, reps = PROJ, DOTS, BATCH, PARTICLES, SPP, 2
        scene = _scene()
    rng = np.random.default_rng(0)
    pats = _dot_frames(batch, rng, proj, n_dots)
    stripe = max(1, proj[0] // 16)
    stripes = np.zeros((1, *proj[::-1]), np.float32)
    stripes[0, :, (np.arange(proj[0]) // stripe) % 2 == 1] = 1.0
    full_s, full = _timed(lambda: scene.render_patterns(stripes), reps)
    ptr_s, ptr = _timed(lambda: scene.render_patterns(pats[:1], spp=1, integrator="ptracer"), reps)
    lit = LitTracer(scene, per_pixel=particles, batch=batch)
    lit_s, ours = _timed(lambda: lit.render(pats[:1], seed=1), reps + 1)
    batch_s, _ = _timed(lambda: lit.render(pats, seed=2), reps)
    gain = 0.8 / float(np.percentile(full[0], 99.5))
    a, b = _detections(ours[0], gain), _detections(ptr[0], gain)
    dist, _ = cKDTree(b.uv).query(a.uv) if len(a) and len(b) else (np.empty(0), None)
    matched = dist < 0.5
    return {
        "reference_s": round(ptr_s, 3),
        "ours_s": round(lit_s, 3),
        "dot_over_full": round(lit_s / full_s, 4),
        "dot_over_full_batched": round(batch_s / batch / full_s, 4),
        "ptracer_dot_over_full": round(ptr_s / full_s, 4),
        "full_s": round(full_s, 3),
        "ptracer_dot_s": round(ptr_s, 3),
        "lit_dot_s": round(lit_s, 3),
        "lit_batch_dot_s": round(batch_s / batch, 3),
        "smoke": smoke,
        "dots": n_dots,
        "batch": batch,
        "sparse_particles": particles,
        "spp": spp,
        "energy_ratio": round(float(ours[0].sum() / ptr[0].sum()), 5),
        "found_lit": len(a),
        "found_ptracer": len(b),
        "matched_fraction": round(float(matched.sum() / max(len(b), 1)), 4),
        "median_match_px": round(float(np.median(dist[matched])), 4) if matched.any() else None,
        "load_1min": round(os.getloadavg()[0], 2),
    }


BENCHMARKS = {"sparse_frame": bench_sparse_frame}
