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


BENCHMARKS = {"gray_code_scan": bench_gray_code_scan, "multiplexed_dots": bench_multiplexed_dots}
