"""Sampling-study benchmarks (paper section 4) on a 1000 x 1600 grid.

``reconstruct_k{800,6000,50000,400000}``: Delaunay-linear reconstruction of k scattered
samples (random distinct pixels) onto the 1000 x 1600 grid. Reference: scipy
``LinearNDInterpolator`` built on the samples and evaluated at every cell (NaN outside the hull);
ours: :func:`simlunar.reconstruction.reconstruct` with ``outside="nan"`` (the same output;
``ours_nearest_s`` is the default nearest-sample fill). ``agree_frac`` is the fraction of
hull cells where both agree to 1e-9 (the rest sit in co-circular lattice squares where the two
Delaunay codes pick different diagonals).

``sampling_protocol``: the paper's full protocol, 5 strategies (grid, random, gradient, entropy,
wavelet) x 11 densities (1/2 .. 1/2048), ``SIMLUNAR_BENCH_PROTOCOL_TRIALS`` trials (default 1),
MSE/GRAD/SAL, on one synthetic 1000 x 1600 lunar scene. Reference path: scikit-image rank
entropy on the padded 8-bit image, ``Generator.choice(p=..., replace=False)`` for the weighted
draws, ``rng.choice`` for random, scipy ``LinearNDInterpolator`` with nearest fill outside the
hull; the same gradient/wavelet/saliency maps and grid plans as ours. Ours:
:func:`simlunar.study.sampling.run_sampling_study` (one process).

``sampling_protocol_20trials``: ours only, the full 20-trial protocol on the same scene with
``workers=2`` (figure: seconds; the target is < 60 s on 2 cores).
"""

from __future__ import annotations

import os
import time

import numpy as np

SHAPE = (1000, 1600)
#: ``smoke=True``: the grid of every sampling benchmark (same code, tiny size)
SMOKE_SHAPE = (60, 96)
PROTOCOL_TRIALS = int(os.environ.get("SIMLUNAR_BENCH_PROTOCOL_TRIALS", "1"))


def lunar_scene(shape=SHAPE, seed=0, *, bed_std=0.05, n_craters=600, n_rocks=600):
    """Synthetic lunar plain (pixel units) and its overhead Lambert image (no shadows).

    fBm bed (power ~ f^-4) + bowl craters with rims + hemispherical rocks, as in
    ``tests/study/test_sampling.py`` (crater and rock counts scaled to the area).
    """
    rng = np.random.default_rng(seed)
    rows, cols = shape
    fy = np.fft.fftfreq(rows)[:, None]
    fx = np.fft.rfftfreq(cols)[None, :]
    f = np.hypot(fy, fx)
    f[0, 0] = 1.0
    spec = (rng.standard_normal(f.shape) + 1j * rng.standard_normal(f.shape)) * f**-2.0
    spec[0, 0] = 0.0
    h = np.fft.irfft2(spec, s=shape)
    h *= bed_std / h.std()
    for _ in range(n_craters):
        rad = min(rng.pareto(1.5) * 4 + 3, 40)
        r0, c0 = rng.uniform(0, rows), rng.uniform(0, cols)
        r_lo, r_hi = max(int(r0 - 3 * rad), 0), min(int(r0 + 3 * rad) + 1, rows)
        c_lo, c_hi = max(int(c0 - 3 * rad), 0), min(int(c0 + 3 * rad) + 1, cols)
        rr, cc = np.mgrid[r_lo:r_hi, c_lo:c_hi]
        d = np.hypot(rr - r0, cc - c0) / rad
        rim = 0.07 * rad * np.exp(-(((d - 1) / 0.25) ** 2)) * (d < 3)
        h[r_lo:r_hi, c_lo:c_hi] += np.where(d < 1, 0.4 * rad * (d**2 - 1) + 0.07 * rad, rim)
    for _ in range(n_rocks):
        rad = rng.uniform(1, 4)
        r0, c0 = rng.uniform(0, rows), rng.uniform(0, cols)
        r_lo, r_hi = max(int(r0 - rad), 0), min(int(r0 + rad) + 2, rows)
        c_lo, c_hi = max(int(c0 - rad), 0), min(int(c0 + rad) + 2, cols)
        rr, cc = np.mgrid[r_lo:r_hi, c_lo:c_hi]
        d2 = ((rr - r0) ** 2 + (cc - c0) ** 2) / rad**2
        h[r_lo:r_hi, c_lo:c_hi] += np.where(d2 < 1, rad * np.sqrt(np.maximum(1 - d2, 0)), 0.0)
    gy, gx = np.gradient(h)
    return h, 1.0 / np.sqrt(1.0 + gx**2 + gy**2)


def _cells(shape):
    rr, cc = np.mgrid[0 : shape[0], 0 : shape[1]]
    return np.column_stack((rr.ravel(), cc.ravel())).astype(np.float64)


def _reconstruct_bench(k: int, *, smoke: bool = False) -> dict:
    from scipy.interpolate import LinearNDInterpolator

    from simlunar.planner import plan
    from simlunar.reconstruction import reconstruct

    shape = SMOKE_SHAPE if smoke else SHAPE
    if smoke:  # the same fraction of the cells
        k = max(8, round(k * shape[0] * shape[1] / (SHAPE[0] * SHAPE[1])))
        h, _ = lunar_scene(shape, n_craters=5, n_rocks=5)
    else:
        h, _ = lunar_scene()
    p = plan("random", k, shape=shape, rng=k)
    pts, vals = p.rc.astype(np.float64), h[p.rows, p.cols]
    # load / compile both paths outside the timing
    warm = np.array([[0.0, 0.0], [0.0, 19.0], [19.0, 0.0], [19.0, 19.0], [7.0, 11.0]])
    reconstruct(warm, warm[:, 0], (20, 20))
    LinearNDInterpolator(warm, warm[:, 0])(_cells((20, 20)))
    t0 = time.perf_counter()
    ref = LinearNDInterpolator(pts, vals)(_cells(shape)).reshape(shape)
    ref_s = time.perf_counter() - t0
    ours_t, near_t = [], []
    for _ in range(1 if smoke else 3):
        t0 = time.perf_counter()
        ours = reconstruct(pts, vals, shape, outside="nan")
        ours_t.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        reconstruct(pts, vals, shape)
        near_t.append(time.perf_counter() - t0)
    inside = np.isfinite(ref)
    agree = np.abs(ours[inside] - ref[inside]) <= 1e-9
    return {
        "reference_s": round(ref_s, 4),
        "ours_s": round(float(np.median(ours_t)), 4),
        "ours_nearest_s": round(float(np.median(near_t)), 4),
        "smoke": smoke,
        "k": k,
        "agree_frac": round(float(agree.mean()), 5),
        "hull_nan_match": bool(np.array_equal(np.isnan(ours), ~inside)),
    }


def _reference_protocol(depth, image, densities, trials, seed):
    """The straightforward path: library-call-per-step with the reference tools."""
    from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator
    from skimage.filters.rank import entropy as sk_entropy

    from simlunar.features import feature_map, to_uint8
    from simlunar.metrics import depth_gradient_weights
    from simlunar.planner import plan

    rng = np.random.default_rng(seed)
    n = depth.size
    u8 = to_uint8(image)
    maps = {
        "gradient": feature_map("gradient", image),
        "entropy": sk_entropy(np.pad(u8, 4, mode="symmetric"), np.ones((9, 9), bool))[4:-4, 4:-4],
        "wavelet": feature_map("wavelet", image),
    }
    wg = depth_gradient_weights(depth).ravel()
    ws = feature_map("saliency", image).ravel()
    cells = _cells(depth.shape)
    truth = depth.ravel()
    errors = []
    for strategy in ("grid", "random", "gradient", "entropy", "wavelet"):
        for _ in range(trials):
            for d in densities:
                k = round(d * n)
                if strategy == "grid":
                    flat = plan("grid", k, shape=depth.shape, rng=rng).flat
                elif strategy == "random":
                    flat = rng.choice(n, k, replace=False)
                else:
                    # Generator.choice needs >= k non-zero weights; a floor of 1e-9 of the
                    # mean weight draws zero-weight pixels last, as ours does
                    w = maps[strategy].ravel() + 1e-9 * maps[strategy].mean()
                    flat = rng.choice(n, k, replace=False, p=w / w.sum())
                pts = np.column_stack(np.divmod(flat, depth.shape[1])).astype(np.float64)
                rec = LinearNDInterpolator(pts, truth[flat])(cells)
                out = np.isnan(rec)
                if out.any():
                    rec[out] = NearestNDInterpolator(pts, truth[flat])(cells[out])
                e2 = (rec - truth) ** 2
                errors.append((e2.mean(), wg @ e2 / wg.sum(), ws @ e2 / ws.sum()))
    return errors


def sampling_protocol(*, smoke: bool = False) -> dict:
    """The protocol vs the reference path (``smoke``: a 60 x 96 scene, densities 1/2 .. 1/32)."""
    from simlunar.study.sampling import SamplingStudyOptions, paper_densities, run_sampling_study

    if smoke:
        depth, image = lunar_scene(SMOKE_SHAPE, n_craters=5, n_rocks=5)
        dens = paper_densities()[:5]
    else:
        depth, image = lunar_scene()
        dens = paper_densities()
    trials = 1 if smoke else PROTOCOL_TRIALS
    small = lunar_scene((64, 96), 1, n_craters=5, n_rocks=5)
    run_sampling_study(
        *small, SamplingStudyOptions(densities=dens[:5], trials=1), rng=0
    )  # warm the kernels
    t0 = time.perf_counter()
    _reference_protocol(depth, image, dens, trials, 0)
    ref_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    opts = SamplingStudyOptions(densities=dens, trials=trials)
    res = run_sampling_study(depth, image, opts, rng=0)
    ours_s = time.perf_counter() - t0
    return {
        "reference_s": round(ref_s, 2),
        "ours_s": round(ours_s, 2),
        "smoke": smoke,
        "trials": trials,
        "reconstructions": 5 * len(dens) * trials,
        "wavelet_mse_score": round(res.scores["mse"]["wavelet"], 3),
    }


def sampling_protocol_20trials(*, smoke: bool = False) -> dict:
    """The 20-trial protocol on 2 workers (``smoke``: 2 trials, 5 densities, a 60 x 96 scene)."""
    from simlunar.study.sampling import SamplingStudyOptions, paper_densities, run_sampling_study

    small = lunar_scene((64, 96), 1, n_craters=5, n_rocks=5)
    run_sampling_study(
        *small, SamplingStudyOptions(densities=paper_densities()[:5], trials=1), rng=0
    )
    if smoke:
        depth, image = lunar_scene(SMOKE_SHAPE, n_craters=5, n_rocks=5)
        opts = SamplingStudyOptions(densities=paper_densities()[:5], trials=2)
    else:
        depth, image = lunar_scene()
        opts = SamplingStudyOptions(trials=20)
    t0 = time.perf_counter()
    res = run_sampling_study(depth, image, opts, rng=0, workers=2)
    ours_s = time.perf_counter() - t0
    scores = res.scores["mse"]
    return {
        "reference_s": None,
        "ours_s": round(ours_s, 2),
        "workers": 2,
        "smoke": smoke,
        "reconstructions": 5 * len(res.densities) * opts.trials,  # the densities run
        **{f"mse_score_{s}": round(v, 3) for s, v in scores.items()},
    }


def _reconstruct_k(k: int):
    def bench(*, smoke: bool = False) -> dict:
        return _reconstruct_bench(k, smoke=smoke)

    bench.__name__ = f"reconstruct_k{k}"
    return bench


BENCHMARKS = {
    "reconstruct_k800": _reconstruct_k(800),
    "reconstruct_k6000": _reconstruct_k(6000),
    "reconstruct_k50000": _reconstruct_k(50_000),
    "reconstruct_k400000": _reconstruct_k(400_000),
    "sampling_protocol": sampling_protocol,
    "sampling_protocol_20trials": sampling_protocol_20trials,
}
