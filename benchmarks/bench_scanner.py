"""Scanner benchmarks: gray-code scan with inverses by linearity, multiplexed dot scanning.

``gray_code_scan``: a 1024 x 768 projector gray-code scan of a moonyard terrain seen by a
512 x 512 camera. Reference: render every pattern and every inverse (2 * bits + 2 renders);
ours: render the patterns, white and black and get the inverses by linearity (bits + 2). Both
then add per-frame sensor noise and decode; the decoded correspondences must agree.

``multiplexed_dots``: dots planned at random over the 1024 x 768 projector, scheduled into frames
by epipolar segments (:func:`simlunar.scanner.dots.schedule_dots`). Reference: the exact
one-dot-per-frame scan; to keep the benchmark short it is run on a random subset of the dots
and its time extrapolated per dot (``reference_s`` = measured time per exact frame x dots;
``exact_subset`` says how many were rendered). The depth difference between the two modes on
the subset is compared with the guide pixel's footprint.

``dot_schedule``: the DLP rig's 10 % rescan (1024 x 768 projector, 2048 x 1536 camera, the full
moonyard, the rig aimed at it as the scanner study does; nothing rendered): 10 % of the projector
pixels at random (seeded) scheduled by :func:`simlunar.scanner.dots.dot_schedule`, with its
frame count, lower bound and time. Reference: the previous scheduler (conflict pairs from a
k-d tree of segment samples gathered in a Python set, greedy colouring in index order), kept
here, timed against the new one on the same ``REFERENCE_SUBSET`` dots.
"""

from __future__ import annotations

import os
import time

import numpy as np

SPP = int(os.environ.get("SIMLUNAR_BENCH_SCANNER_SPP", "2"))
#: dot detection threshold (frame units; white frame at 0.8): a one-pixel dot of the 1024-column
#: projector lights a quarter of a 512-column camera pixel, so dark soil gives ~0.02
ABS_THRESHOLD = 0.01
DOT_SPP = int(os.environ.get("SIMLUNAR_BENCH_SCANNER_DOT_SPP", "16"))


def _setup(cam_size, *, max_depth=3, seed=0, spp=SPP):
    from simlunar.imaging.sensor import SensorModel
    from simlunar.study import scanner as st
    from simlunar.terrain import generate

    terr = generate("moonyard", rng=seed, scale=0.35).terrain
    rig = st.aim_rig_at_terrain(terr, proj_size=(1024, 768), cam_size=cam_size)
    cap = st.RenderCapture(
        terr, rig, max_depth=max_depth, spp=spp, seed=seed, sensor=SensorModel(), rng=seed
    )
    return terr, rig, cap


def bench_gray_code_scan() -> dict:
    from simlunar.scanner import gray_code as gc
    from simlunar.scanner import modes

    _, rig, cap = _setup((512, 512))
    cap.render(np.ones((1, 768, 1024), np.float32))  # warm up: kernels compiled once
    r0 = cap.renders
    t0 = time.perf_counter()
    ref = modes.gray_code_scan(cap, rig, inverses="render")
    t_ref = time.perf_counter() - t0
    r_ref = cap.renders - r0
    t0 = time.perf_counter()
    ours = modes.gray_code_scan(cap, rig, inverses="linearity")
    t_ours = time.perf_counter() - t0
    r_ours = cap.renders - r0 - r_ref
    both = ref.decode.valid & ours.decode.valid
    bits = gc.num_bits(1024) + gc.num_bits(768)
    return {
        "reference_s": round(t_ref, 3),
        "ours_s": round(t_ours, 3),
        "renders": r_ours,
        "reference_renders": r_ref,
        "target_renders": bits + 2,
        "spp": SPP,
        "valid_fraction": round(float(ours.decode.valid.mean()), 4),
        "same_column": round(float(np.mean(ref.decode.col[both] == ours.decode.col[both])), 4),
    }


def bench_multiplexed_dots(n_dots: int = 3000, exact_subset: int = 100) -> dict:
    from simlunar.scanner import modes, rigs
    from simlunar.study import scanner as st

    # a one-pixel dot covers a quarter of a camera pixel: with few samples per pixel the
    # Monte Carlo render misses it altogether, so dots get DOT_SPP samples
    terr, rig, cap = _setup((512, 384), max_depth=2, spp=DOT_SPP)
    rng = np.random.default_rng(1)
    flat = rng.choice(1024 * 768, size=n_dots, replace=False)
    rc = np.stack([flat // 1024, flat % 1024], axis=-1)
    uv = np.c_[rc[:, 1] + 0.5, rc[:, 0] + 0.5]
    depth_range = st.depth_range_from_terrain(terr, rig)
    cap.render(np.zeros((1, 768, 1024), np.float32))  # warm up
    t0 = time.perf_counter()
    multi = modes.dot_scan(cap, rig, uv, depth_range=depth_range, abs_threshold=ABS_THRESHOLD)
    t_multi = time.perf_counter() - t0
    sub = rng.choice(n_dots, size=exact_subset, replace=False)
    t0 = time.perf_counter()
    exact = modes.dot_scan(
        cap, rig, uv[sub], depth_range=depth_range, exact=True, abs_threshold=ABS_THRESHOLD
    )
    t_exact = time.perf_counter() - t0
    d_m = multi.depth[rc[sub, 0], rc[sub, 1]]
    d_e = exact.depth[rc[sub, 0], rc[sub, 1]]
    ok = np.isfinite(d_m) & np.isfinite(d_e)
    diff = float(np.median(np.abs(d_m[ok] - d_e[ok])))
    fp = rigs.footprint(rig, float(np.median(d_e[ok])))
    frames = multi.renders - 1  # minus the black frame
    return {
        "reference_s": round(t_exact / exact_subset * n_dots, 3),
        "ours_s": round(t_multi, 3),
        "dots": n_dots,
        "spp": DOT_SPP,
        "renders": multi.renders,
        "dots_per_render": round(n_dots / frames, 1),
        "found_fraction": round(float(multi.found.mean()), 4),
        "exact_found_fraction": round(float(exact.found.mean()), 4),
        "multiplexed_found_on_subset": round(float(multi.found[sub].mean()), 4),
        "exact_subset": exact_subset,
        "exact_subset_s": round(t_exact, 3),
        "median_depth_diff_m": round(diff, 7),
        "footprint_m": round(fp, 6),
        "diff_over_footprint": round(diff / fp, 4),
    }


#: dots of the dot_schedule benchmark that the previous scheduler is timed on
REFERENCE_SUBSET = 3000


def _reference_schedule(rig, proj_uv, *, depth_range, min_proj_spacing=8.0, min_cam_spacing=6.0):
    """The scheduler simlunar had before the epipolar one (conflict pairs in a Python set)."""
    from scipy.spatial import cKDTree

    from simlunar.scanner.dots import epipolar_segments

    seg = epipolar_segments(rig, proj_uv, depth_range)
    sep = float(min_cam_spacing)
    h = sep / 2.0
    lengths = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=-1)
    counts = np.ceil(lengths / h).astype(int) + 1
    owner = np.repeat(np.arange(len(seg)), counts)
    t = np.concatenate([np.linspace(0.0, 1.0, c) for c in counts])
    pts = seg[owner, 0] + t[:, None] * (seg[owner, 1] - seg[owner, 0])
    pairs = cKDTree(pts).query_pairs(sep + h, output_type="ndarray")
    a, b = owner[pairs[:, 0]], owner[pairs[:, 1]]
    keep = a != b
    conflicts = {(int(min(x, y)), int(max(x, y))) for x, y in zip(a[keep], b[keep])}
    pp = cKDTree(proj_uv).query_pairs(float(min_proj_spacing), output_type="ndarray")
    for x, y in pp:
        conflicts.add((int(min(x, y)), int(max(x, y))))
    n = len(proj_uv)
    neighbours: list[list[int]] = [[] for _ in range(n)]
    for x, y in conflicts:
        neighbours[x].append(y)
        neighbours[y].append(x)
    colour = np.full(n, -1, dtype=np.int64)
    for i in range(n):
        used = {int(colour[j]) for j in neighbours[i] if colour[j] >= 0}
        c = 0
        while c in used:
            c += 1
        colour[i] = c
    return [np.flatnonzero(colour == c) for c in range(int(colour.max()) + 1)]


def bench_dot_schedule(fraction: float = 0.1) -> dict:
    from simlunar.scanner import dots
    from simlunar.study import scanner as st
    from simlunar.terrain import generate

    proj, cam = (1024, 768), (2048, 1536)
    terr = generate("moonyard", rng=0).terrain
    rig = st.aim_rig_at_terrain(terr, proj_size=proj, cam_size=cam)
    depth_range = st.depth_range_from_terrain(terr, rig)
    rng = np.random.default_rng(0)
    n = round(fraction * proj[0] * proj[1])
    flat = rng.choice(proj[0] * proj[1], size=n, replace=False)
    uv = np.c_[flat % proj[0] + 0.5, flat // proj[0] + 0.5]
    dots.dot_schedule(rig, uv[:500], depth_range=depth_range)  # load the compiled kernels
    t0, c0 = time.perf_counter(), time.process_time()
    sch = dots.dot_schedule(rig, uv, depth_range=depth_range)
    t_full, c_full = time.perf_counter() - t0, time.process_time() - c0
    sub = uv[:REFERENCE_SUBSET]
    t0 = time.perf_counter()
    ref = _reference_schedule(rig, sub, depth_range=depth_range)
    t_ref = time.perf_counter() - t0
    t0 = time.perf_counter()
    ours_sub = dots.dot_schedule(rig, sub, depth_range=depth_range)
    t_ours = time.perf_counter() - t0
    return {
        "reference_s": round(t_ref, 3),
        "ours_s": round(t_ours, 4),
        "subset": REFERENCE_SUBSET,
        "reference_frames": len(ref),
        "subset_frames": len(ours_sub.frames),
        "subset_lower_bound": ours_sub.lower_bound,
        "dots": n,
        "frames": len(sch.frames),
        "lower_bound": sch.lower_bound,
        "frames_over_bound": round(sch.frames_over_bound, 3),
        "dots_per_frame": round(n / len(sch.frames), 1),
        "schedule_s": round(t_full, 3),
        "schedule_cpu_s": round(c_full, 3),
    }


BENCHMARKS = {
    "gray_code_scan": bench_gray_code_scan,
    "multiplexed_dots": bench_multiplexed_dots,
    "dot_schedule": bench_dot_schedule,
}
