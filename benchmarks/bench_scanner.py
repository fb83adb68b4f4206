"""Scanner benchmarks: gray-code scan with inverses by linearity, multiplexed dot scanning.

``gray_code_scan``: a 1024 x 768 projector gray-code scan of a moonyard terrain seen by a
512 x 512 camera. Reference: render every pattern and every inverse (2 * bits + 2 renders);
ours: render the patterns, white and black and get the inverses by linearity (bits + 2). Both
then add per-frame sensor noise and decode; the decoded correspondences must agree.

``multiplexed_dots``: dots planned at random over the 1024 x 768 projector, scheduled into frames
by epipolar segments (:func:`simlunar.scanner.scheduling.schedule_dots`). Reference: the exact
one-dot-per-frame scan; to keep the benchmark short it is run on a random subset of the dots
and its time extrapolated per dot (``reference_s`` = measured time per exact frame x dots;
``exact_subset`` says how many were rendered). The depth difference between the two modes on
the subset is compared with the guide pixel's footprint.

``dot_schedule``: the DLP rig's 10 % rescan (1024 x 768 projector, 2048 x 1536 camera, the full
moonyard, the rig aimed at it as the scanner study does; nothing rendered): 10 % of the projector
pixels at random (seeded) scheduled by :func:`simlunar.scanner.scheduling.dot_schedule`, with its
frame count, lower bound and time. Reference: the previous scheduler (conflict pairs from a
k-d tree of segment samples gathered in a Python set, greedy colouring in index order), kept
here, timed against the new one on the same ``REFERENCE_SUBSET`` dots.

``scanner_dlp``: one gray-code scan at DLP size (the full moonyard, 1024 x 768 projector,
2048 x 1536 camera, spp 8, the DLP experiment's sensor, lens PSF and sub-pixel refinement) in
a fresh process, so its peak memory is its own: ``render_s`` (Mitsuba), ``rest_s`` (all other
work of the scan) and ``peak_rss_gb``. Reference: the former float64 path (blur of the whole
stack, NumPy Poisson per frame, decode and refinement of the stack) on the same rendered
frames, in a second process; ``ratio`` compares the two rests.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

SPP = int(os.environ.get("SIMLUNAR_BENCH_SCANNER_SPP", "2"))
#: dot detection threshold (frame units; white frame at 0.8): a one-pixel dot of the 1024-column
#: projector lights a quarter of a 512-column camera pixel, so dark soil gives ~0.02
ABS_THRESHOLD = 0.01
DOT_SPP = int(os.environ.get("SIMLUNAR_BENCH_SCANNER_DOT_SPP", "16"))
#: ``smoke=True``: projector and camera (width, height), moonyard scale (same code paths)
SMOKE_PROJ, SMOKE_CAM, SMOKE_SCALE = (64, 48), (48, 48), 0.08


def _setup(cam_size, *, max_depth=3, seed=0, spp=SPP, proj_size=(1024, 768), scale=0.35):
    from simlunar.config.translate import preset_params
    from simlunar.imaging.sensor import SensorModel
    from simlunar.render.capture import CaptureOptions, RenderCapture
    from simlunar.study import scanner as st
    from simlunar.terrain import generate

    terr = generate(preset_params("moonyard"), rng=seed, scale=scale).terrain
    rig = st.aim_rig_at_terrain(terr, proj_size=proj_size, cam_size=cam_size)
    opts = CaptureOptions(max_depth=max_depth, spp=spp, seed=seed)
    cap = RenderCapture(terr, rig, opts, sensor=SensorModel(), rng=seed)
    return terr, rig, cap


def bench_gray_code_scan(*, smoke: bool = False) -> dict:
    from simlunar.scanner import gray_code as gc
    from simlunar.scanner.gray_code import GrayCodeOptions, gray_code_scan

    proj = SMOKE_PROJ if smoke else (1024, 768)
    if smoke:
        _, rig, cap = _setup(SMOKE_CAM, proj_size=proj, scale=SMOKE_SCALE, spp=1)
    else:
        _, rig, cap = _setup((512, 512))
    cap.render(np.ones((1, proj[1], proj[0]), np.float32))  # warm up: kernels compiled once
    r0 = cap.renders
    t0 = time.perf_counter()
    ref = gray_code_scan(cap, rig, GrayCodeOptions(inverses="render"))
    t_ref = time.perf_counter() - t0
    r_ref = cap.renders - r0
    t0 = time.perf_counter()
    ours = gray_code_scan(cap, rig, GrayCodeOptions(inverses="linearity"))
    t_ours = time.perf_counter() - t0
    r_ours = cap.renders - r0 - r_ref
    both = ref.decode.valid & ours.decode.valid
    bits = gc.num_bits(proj[0]) + gc.num_bits(proj[1])
    return {
        "smoke": smoke,
        "reference_s": round(t_ref, 3),
        "ours_s": round(t_ours, 3),
        "renders": r_ours,
        "reference_renders": r_ref,
        "target_renders": bits + 2,
        "spp": SPP,
        "valid_fraction": round(float(ours.decode.valid.mean()), 4),
        "same_column": round(float(np.mean(ref.decode.col[both] == ours.decode.col[both])), 4),
    }


def bench_multiplexed_dots(
    n_dots: int = 3000, exact_subset: int = 100, *, smoke: bool = False
) -> dict:
    from simlunar.scanner import rigs
    from simlunar.scanner.dot_scan import DotOptions, dot_scan
    from simlunar.study import scanner as st

    # a one-pixel dot covers a quarter of a camera pixel: with few samples per pixel the
    # Monte Carlo render misses it altogether, so dots get DOT_SPP samples
    W, H = SMOKE_PROJ if smoke else (1024, 768)
    if smoke:
        n_dots, exact_subset = 12, 4
        terr, rig, cap = _setup(SMOKE_CAM, max_depth=2, spp=4, proj_size=(W, H), scale=SMOKE_SCALE)
    else:
        terr, rig, cap = _setup((512, 384), max_depth=2, spp=DOT_SPP)
    rng = np.random.default_rng(1)
    flat = rng.choice(W * H, size=n_dots, replace=False)
    rc = np.stack([flat // W, flat % W], axis=-1)
    uv = np.c_[rc[:, 1] + 0.5, rc[:, 0] + 0.5]
    depth_range = st.depth_range_from_terrain(terr, rig)
    # warm up with one lit dot (an all-dark pattern is skipped by the capture, compiling nothing)
    warm = np.zeros((1, H, W), np.float32)
    warm[0, H // 2, W // 2] = 1.0
    cap.render(warm)
    t0 = time.perf_counter()
    multi = dot_scan(
        cap, rig, uv, depth_range=depth_range, options=DotOptions(abs_threshold=ABS_THRESHOLD)
    )
    t_multi = time.perf_counter() - t0
    sub = rng.choice(n_dots, size=exact_subset, replace=False)
    t0 = time.perf_counter()
    exact = dot_scan(
        cap,
        rig,
        uv[sub],
        depth_range=depth_range,
        options=DotOptions(exact=True, abs_threshold=ABS_THRESHOLD),
    )
    t_exact = time.perf_counter() - t0
    d_m = multi.depth[rc[sub, 0], rc[sub, 1]]
    d_e = exact.depth[rc[sub, 0], rc[sub, 1]]
    ok = np.isfinite(d_m) & np.isfinite(d_e)
    diff = float(np.median(np.abs(d_m[ok] - d_e[ok]))) if ok.any() else float("nan")
    fp = rigs.footprint(rig, float(np.median(d_e[ok]))) if ok.any() else float("nan")
    frames = max(multi.renders - 1, 1)  # minus the black frame
    return {
        "smoke": smoke,
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


def bench_dot_schedule(fraction: float = 0.1, *, smoke: bool = False) -> dict:
    from simlunar.config.translate import preset_params
    from simlunar.scanner import scheduling
    from simlunar.study import scanner as st
    from simlunar.terrain import generate

    proj, cam = (1024, 768), (2048, 1536)
    subset = REFERENCE_SUBSET
    if smoke:
        proj, cam, subset = SMOKE_PROJ, SMOKE_CAM, 60
    terr = generate(preset_params("moonyard"), rng=0, scale=SMOKE_SCALE if smoke else 1.0).terrain
    rig = st.aim_rig_at_terrain(terr, proj_size=proj, cam_size=cam)
    depth_range = st.depth_range_from_terrain(terr, rig)
    rng = np.random.default_rng(0)
    n = round(fraction * proj[0] * proj[1])
    flat = rng.choice(proj[0] * proj[1], size=n, replace=False)
    uv = np.c_[flat % proj[0] + 0.5, flat // proj[0] + 0.5]
    scheduling.dot_schedule(rig, uv[: min(500, n)], depth_range=depth_range)  # load the kernels
    t0, c0 = time.perf_counter(), time.process_time()
    sch = scheduling.dot_schedule(rig, uv, depth_range=depth_range)
    t_full, c_full = time.perf_counter() - t0, time.process_time() - c0
    sub = uv[:subset]
    t0 = time.perf_counter()
    ref = _reference_schedule(rig, sub, depth_range=depth_range)
    t_ref = time.perf_counter() - t0
    t0 = time.perf_counter()
    ours_sub = scheduling.dot_schedule(rig, sub, depth_range=depth_range)
    t_ours = time.perf_counter() - t0
    return {
        "reference_s": round(t_ref, 3),
        "ours_s": round(t_ours, 4),
        "smoke": smoke,
        "subset": subset,
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


#: the DLP rig of experiments/scanner_ambiguity_dlp.yaml: projector and camera (width, height)
DLP_PROJ, DLP_CAM = (1024, 768), (2048, 1536)
DLP_SPP = 8


def _dlp_setup(smoke: bool = False):
    from simlunar.config.translate import preset_params
    from simlunar.imaging.sensor import SensorModel
    from simlunar.render.capture import CaptureOptions, RenderCapture
    from simlunar.study import scanner as st
    from simlunar.terrain import generate

    proj, cam = _dlp_sizes(smoke)
    # the full 971 x 1674 moonyard (smoke: a small part of it)
    terr = generate(preset_params("moonyard"), rng=0, scale=SMOKE_SCALE if smoke else 1.0).terrain
    rig = st.aim_rig_at_terrain(terr, proj_size=proj, cam_size=cam, cam_fov_x=np.radians(60.0))
    sensor = SensorModel(full_well_e=20000.0, read_noise_e=5.0, bits=10)
    opts = CaptureOptions(max_depth=3, spp=1 if smoke else DLP_SPP, seed=0, camera_blur=1.0)
    cap = RenderCapture(terr, rig, opts, sensor=sensor, rng=0)
    return terr, rig, cap


def _dlp_sizes(smoke: bool):
    """Projector and camera (width, height) of the DLP benchmark (``smoke``: tiny ones)."""
    return (SMOKE_PROJ, SMOKE_CAM) if smoke else (DLP_PROJ, DLP_CAM)


def _warm_up_compiled():
    """Load (or compile) the numba kernels before timing: a tiny gray-code scan of each step."""
    from simlunar.imaging.blur import gaussian_blur
    from simlunar.imaging.sensor import SensorModel, apply_sensor
    from simlunar.scanner import gray_code as gc
    from simlunar.scanner.subpixel import refine_subpixel

    apply_sensor(np.ones((4, 4), np.float32), SensorModel(), rng=0)
    gaussian_blur(np.ones((12, 12), np.float32), 1.0)
    st = gc.encode(8, 4).astype(np.float32) / 255
    d = gc.decode(st, np.ones((4, 8)), np.zeros((4, 8)), proj_shape=(4, 8), black_threshold=0.1)
    refine_subpixel(d, st)


def _dlp_worker(mode: str, frames_path: str, smoke: bool = False) -> dict:
    """One DLP gray-code scan in this process; ``mode`` "ours" or "reference".

    ``ours`` renders and times the scan (render vs the rest) and saves the noise-free
    radiance frames; ``reference`` loads them and runs the pre-streaming float64 path on them
    (lens blur of the stack, NumPy Poisson per frame, decode and refinement of the stack).
    """
    import resource

    from simlunar.scanner import gray_code as gc
    from simlunar.scanner.gray_code import GrayCodeOptions, gray_code_scan
    from simlunar.scanner.triangulate import Correspondences, depth_at_proj_pixels, triangulate

    _warm_up_compiled()
    _terrain, rig, cap = _dlp_setup(smoke)
    proj, _ = _dlp_sizes(smoke)
    if mode == "ours":
        render_s = save_s = 0.0
        saved = []
        orig = cap.scene.render_patterns

        def timed(pats, **kw):
            nonlocal render_s, save_s
            t = time.perf_counter()
            out = orig(pats, **kw)
            t1 = time.perf_counter()
            # the raw frames for the reference path (not timed: written to disk at once)
            saved.append(f"{frames_path}.{len(saved)}.npy")
            np.save(saved[-1], out)
            render_s += t1 - t
            save_s += time.perf_counter() - t1
            return out

        cap.scene.render_patterns = timed
        t0 = time.perf_counter()
        g = gray_code_scan(cap, rig, GrayCodeOptions(subpixel=True))
        total = time.perf_counter() - t0 - save_s
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
        # raw frames in render order (white, black, then the bit patterns) for the reference;
        # the capture skips the all-dark black pattern (its render is exactly zero: the
        # projector is the only emitter), so its zero frame is put back in its place
        raw = np.concatenate([np.load(f) for f in saved])
        n_bits = gc.num_bits(proj[0]) + gc.num_bits(proj[1])
        if len(raw) == n_bits + 1:
            raw = np.insert(raw, 1, np.zeros_like(raw[0]), axis=0)
        if len(raw) != n_bits + 2:
            raise RuntimeError(f"expected {n_bits + 2} rendered frames, saved {len(raw)}")
        np.save(frames_path, raw)
        for f in saved:
            os.remove(f)
        dec = g.decode
        out = {"render_s": render_s, "rest_s": total - render_s, "renders": g.renders}
    else:
        import reference_scanner as ref

        raw = np.load(frames_path)  # white, black, patterns: the radiance the scan rendered
        t0 = time.perf_counter()
        H, W = proj[1], proj[0]
        rad = ref.lens_reference(raw, cap.camera_blur)
        white_r, black_r, pats = rad[0], rad[1], rad[2:]
        inv = gc.inverses_by_linearity(pats, white_r, black_r)
        radiance = np.concatenate([gc.interleave(pats, inv), rad[:2]])
        frames = np.stack(
            [ref.apply_sensor_reference(im, cap.sensor, rng=cap.rng) for im in radiance]
        ).astype(np.float64)
        images, white, black = frames[:-2], frames[-2], frames[-1]
        dec = ref.decode_reference(
            images, white, black, proj_shape=(H, W), black_threshold=0.05, white_threshold=0.01
        )
        dec = ref.refine_subpixel_reference(dec, images)
        cloud = triangulate(rig, Correspondences.from_gray(dec), method="plane")
        depth_at_proj_pixels(cloud, rig.guide)
        out = {"rest_s": time.perf_counter() - t0}
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    out["peak_rss_gb"] = peak
    out["valid_fraction"] = float(dec.valid.mean())
    np.savez(frames_path + f".{mode}.npz", col=dec.col, valid=dec.valid, sub=dec.subpixel)
    return out


def bench_scanner_dlp(*, smoke: bool = False) -> dict:
    """One gray-code scan at DLP size (spp 8) in a fresh process; the float64 path on its frames.

    ``render_s``: Mitsuba (scene.render_patterns, 22 frames); ``rest_s``: everything else of
    the scan (lens blur, sensor, decode, refinement, triangulation); ``peak_rss_gb``: the
    scan process's peak resident memory (scene included). ``reference_s`` is the rest of the
    pre-streaming float64 path on the same rendered frames, in a second process.
    """
    root = Path(__file__).resolve().parent.parent
    tmp = root / "build" / ("bench_scanner_dlp_smoke" if smoke else "bench_scanner_dlp")
    tmp.mkdir(parents=True, exist_ok=True)
    frames = str(tmp / "radiance.npy")
    env = {**os.environ, "PYTHONPATH": str(root)}
    res = {}
    for mode in ("ours", "reference"):
        p = subprocess.run(
            [sys.executable, str(Path(__file__).resolve()), "dlp", mode, frames, str(int(smoke))],
            capture_output=True,
            text=True,
            env=env,
            check=False,
        )
        if p.returncode != 0:
            raise RuntimeError(f"scanner_dlp {mode} worker failed:\n{p.stderr[-2000:]}")
        res[mode] = json.loads(p.stdout.strip().splitlines()[-1])
    ours, ref = res["ours"], res["reference"]
    a = dict(np.load(frames + ".ours.npz"))
    b = dict(np.load(frames + ".reference.npz"))
    both = a["valid"] & b["valid"]
    du = a["sub"][..., 0][both] - b["sub"][..., 0][both]
    du = du[np.isfinite(du)]
    for f in (frames, frames + ".ours.npz", frames + ".reference.npz"):
        os.remove(f)
    return {
        "smoke": smoke,
        "reference_s": round(ref["rest_s"], 3),
        "ours_s": round(ours["rest_s"], 3),
        "render_s": round(ours["render_s"], 3),
        "rest_s": round(ours["rest_s"], 3),
        "rest_over_render": round(ours["rest_s"] / ours["render_s"], 3),
        "peak_rss_gb": round(ours["peak_rss_gb"], 3),
        "reference_peak_rss_gb": round(ref["peak_rss_gb"], 3),
        "renders": ours["renders"],
        "spp": 1 if smoke else DLP_SPP,
        "valid_fraction": round(ours["valid_fraction"], 4),
        "reference_valid_fraction": round(ref["valid_fraction"], 4),
        "same_column": round(float(np.mean(a["col"][both] == b["col"][both])), 4),
        "subpixel_rms_diff_px": round(float(np.sqrt(np.mean(du**2))), 4),
        "load_1min": round(os.getloadavg()[0], 2),
    }


BENCHMARKS = {
    "gray_code_scan": bench_gray_code_scan,
    "multiplexed_dots": bench_multiplexed_dots,
    "dot_schedule": bench_dot_schedule,
    "scanner_dlp": bench_scanner_dlp,
}


if __name__ == "__main__" and len(sys.argv) == 5 and sys.argv[1] == "dlp":
    print(json.dumps(_dlp_worker(sys.argv[2], sys.argv[3], smoke=sys.argv[4] == "1")))
