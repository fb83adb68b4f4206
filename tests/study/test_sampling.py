"""The sampling study: protocol bookkeeping, seeding, tables, bad input, the paper's claim."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics import depth_gradient_weights, metric
from simlunar.planner import plan, strategy_weights
from simlunar.plotting.tables import score_tables
from simlunar.progress import reporting
from simlunar.reconstruction import reconstruct
from simlunar.study import sampling
from simlunar.study.sampling import SamplingStudyOptions, paper_densities


def run_sampling_study(depth, image, *, rng, workers=1, **options):
    """The study with its options as keywords (SamplingStudyOptions fields)."""
    return sampling.run_sampling_study(
        depth, image, SamplingStudyOptions(**options), rng=rng, workers=workers
    )


def lunar_dem(shape, rng, *, bed_std=0.05, n_craters=100, n_rocks=100):
    """Height field (pixel units): fBm bed + bowl craters with rims + hemispherical rocks.

    The bed is spectral fBm with power ~ f^-4 scaled to ``bed_std``; craters have radius
    3 + 4 Pareto(1.5) px (capped at 40), depth 0.4 R below a rim 0.07 R high (Pike-like
    depth/diameter ~ 0.2); rocks are hemispheres of radius 1-4 px.
    """
    rows, cols = shape
    fy = np.fft.fftfreq(rows)[:, None]
    fx = np.fft.rfftfreq(cols)[None, :]
    f = np.hypot(fy, fx)
    f[0, 0] = 1.0
    spec = (rng.standard_normal(f.shape) + 1j * rng.standard_normal(f.shape)) * f**-2.0
    spec[0, 0] = 0.0
    h = np.fft.irfft2(spec, s=shape)
    h *= bed_std / h.std()
    rr, cc = np.mgrid[0:rows, 0:cols]
    for _ in range(n_craters):
        r0, c0 = rng.uniform(0, rows), rng.uniform(0, cols)
        rad = min(rng.pareto(1.5) * 4 + 3, 40)
        d = np.hypot(rr - r0, cc - c0) / rad
        rim = 0.07 * rad * np.exp(-(((d - 1) / 0.25) ** 2)) * (d < 3)
        h += np.where(d < 1, 0.4 * rad * (d**2 - 1) + 0.07 * rad, rim)
    for _ in range(n_rocks):
        r0, c0 = rng.uniform(0, rows), rng.uniform(0, cols)
        rad = rng.uniform(1, 4)
        d2 = ((rr - r0) ** 2 + (cc - c0) ** 2) / rad**2
        h += np.where(d2 < 1, rad * np.sqrt(np.maximum(1 - d2, 0)), 0.0)
    return h


def lambert_overhead(h):
    """Lambert shading, nadir view, light from the camera (overhead): I = n . z, no shadows."""
    gy, gx = np.gradient(h)
    return 1.0 / np.sqrt(1.0 + gx**2 + gy**2)


@pytest.fixture(scope="module")
def scene():
    h = lunar_dem((48, 64), np.random.default_rng(3), n_craters=8, n_rocks=8)
    return h, lambert_overhead(h)


DENS = [1 / 4, 1 / 16, 1 / 64]


def test_paper_densities():
    d = paper_densities()
    assert len(d) == 11 and d[0] == 0.5 and d[-1] == 1 / 2048
    np.testing.assert_allclose(np.diff(np.log2(d)), -1.0)


def test_tidy_rows_and_scores(scene):
    depth, image = scene
    res = run_sampling_study(depth, image, densities=DENS, trials=2, rng=0)
    assert len(res.rows) == 5 * 3 * 2 * 3
    assert set(res.rows[0]) == {
        "strategy", "reconstruction", "density", "k", "trial", "metric", "value"
    }  # fmt: skip
    assert {r["reconstruction"] for r in res.rows} == {"linear"}
    assert res.ks == [768, 192, 48]
    assert set(res.scores) == {"mse", "grad", "sal"}
    for m in res.scores:
        assert res.scores[m]["random"] == 1.0
    means = res.mean_errors()["mse"]["wavelet"]
    assert means.shape == (3,)
    vals = [
        r["value"] for r in res.rows
        if r["strategy"] == "wavelet" and r["metric"] == "mse" and r["density"] == 1 / 16
    ]  # fmt: skip
    assert means[1] == pytest.approx(np.mean(vals))


def test_row_values_reproduce_with_the_library(scene):
    # Rebuild one row from its seed with plan -> reconstruct -> metric: the study adds nothing.
    depth, image = scene
    res = run_sampling_study(
        depth, image, densities=DENS, trials=2, rng=5, strategies=["entropy", "random"]
    )
    base = int(np.random.default_rng(5).integers(0, 2**63))
    p = plan("entropy", 192, weights=strategy_weights("entropy", image), shape=depth.shape,
             rng=sampling._seed(base, "entropy", 1, 1, 0))  # fmt: skip
    rec = reconstruct(p.rc, depth[p.rows, p.cols], depth.shape)
    row = {
        r["metric"]: r["value"] for r in res.rows
        if r["strategy"] == "entropy" and r["trial"] == 1 and r["k"] == 192
    }  # fmt: skip
    assert row["mse"] == pytest.approx(metric("mse", rec, depth), rel=1e-10)
    assert row["grad"] == pytest.approx(
        metric("grad", rec, depth, weights=depth_gradient_weights(depth)), rel=1e-10
    )


def test_strategy_seeds_are_independent(scene):
    depth, image = scene
    a = run_sampling_study(
        depth, image, densities=DENS, trials=2, rng=1, strategies=["random", "wavelet"]
    )
    b = run_sampling_study(
        depth, image, densities=DENS, trials=2, rng=1, strategies=["grid", "wavelet"]
    )
    wa = [r for r in a.rows if r["strategy"] == "wavelet"]
    wb = [r for r in b.rows if r["strategy"] == "wavelet"]
    assert wa == wb
    # and trials differ from each other (fresh grid shift per trial)
    g = b.errors("mse")["grid"]
    assert not np.allclose(g[:, 0], g[:, 1])


def test_workers_do_not_change_results(scene):
    depth, image = scene
    kw = dict(densities=DENS, trials=2, rng=4, strategies=["random", "grid"])
    a = run_sampling_study(depth, image, **kw)
    b = run_sampling_study(depth, image, workers=2, **kw)
    assert a.rows == b.rows


def test_feature_maps_computed_once(scene, monkeypatch):
    from simlunar.planner import strategies as strat

    calls = []
    real = strat.feature_map

    def counting(name, image, **opts):
        calls.append(name)
        return real(name, image, **opts)

    monkeypatch.setattr(strat, "feature_map", counting)
    depth, image = scene
    run_sampling_study(
        depth, image, densities=DENS, trials=3, rng=0, metrics=["mse"],
        strategies=["random", "wavelet", "entropy", "wavelet-bn"],
        strategy_options={"wavelet-bn": {"strategy": "wavelet", "blue_noise": True}},
    )  # fmt: skip
    assert sorted(calls) == ["entropy", "wavelet"]


def test_range_noise_and_full_density(scene):
    depth, image = scene
    exact = run_sampling_study(depth, image, densities=[1.0], trials=1, rng=0, metrics=["mse"],
                               strategies=["random"])  # fmt: skip
    assert exact.rows[0]["value"] == 0.0  # every cell sampled, no noise: exact
    noisy = run_sampling_study(depth, image, densities=[1.0], trials=3, rng=0, metrics=["mse"],
                               strategies=["random"], range_noise_std=0.1)  # fmt: skip
    # k = N: the reconstruction is the noisy samples, MSE ~ sigma^2 = 0.01 (3072 cells x 3)
    assert np.mean([r["value"] for r in noisy.rows]) == pytest.approx(0.01, rel=0.1)


def test_tables_layout(scene):
    depth, image = scene
    res = run_sampling_study(depth, image, densities=DENS, trials=1, rng=0)
    # one score table, formatted by plotting.tables (the study returns numbers only)
    md, tex = score_tables([("", res.scores)], strategies=res.strategies, metrics=res.metrics)
    md = [line for line in md.splitlines() if line.startswith("|")]
    assert md[0] == "| Metric | Grid | Random | Gradient | Entropy | Wavelet |"
    assert [line.split("|")[1].strip() for line in md[2:]] == ["MSE", "GRAD", "SAL"]
    assert md[2].split("|")[3].strip().strip("*") == "1.00"
    assert "\\begin{tabular}{lrrrrr}" in tex and "GRAD & " in tex


def test_samples_for_equal_error_summary(scene):
    depth, image = scene
    res = run_sampling_study(depth, image, densities=DENS, trials=1, rng=0, metrics=["mse"])
    out = res.samples_for_equal_error("mse")
    np.testing.assert_allclose(out["random"], 1.0)


def test_score_intervals_and_samples_saved(scene):
    depth, image = scene
    res = run_sampling_study(depth, image, densities=DENS, trials=4, rng=0, metrics=["mse"])
    iv = res.score_intervals("mse", n_boot=200, rng=1)
    for s in res.strategies:
        score, lo, hi = iv.interval(s)
        assert score == pytest.approx(res.scores["mse"][s])  # the point is eq. 4.3
        assert lo <= score <= hi
    assert iv.interval("random") == (1.0, 1.0, 1.0)
    saved = res.samples_saved("mse")
    np.testing.assert_allclose(saved.factor["random"], 1.0)
    assert saved.reference == "random" and saved.ks.tolist() == res.ks
    assert res.samples_saved("mse", reference="grid").factor["grid"] == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"densities": [0.5, 0.0]}, r"densities must lie in \(0, 1\]"),
        ({"densities": [1.5]}, r"densities must lie in \(0, 1\]"),
        (
            {"densities": [1 / 4096]},
            "density 0.000244141 gives k = 1 < 3 samples on a grid of N = 3072",
        ),
        ({"strategies": ["random", "sobel"]}, "unknown strategy 'sobel'"),
        ({"metrics": ["mse", "psnr"]}, "unknown metric 'psnr'"),
        ({"trials": 0}, "trials must be an integer >= 1"),
        ({"depth": "nan"}, "depth contains NaN"),
        ({"image": "nan"}, "image contains NaN"),
        ({"image": "small"}, "same grid"),
        ({"strategy_options": {"wavelet": {"blue_nois": True}}}, "unknown option"),
        ({"strategy_options": {"other": {}}}, "not in the study"),
        ({"range_noise_std": -1.0}, "range_noise_std"),
    ],
)
def test_bad_input(scene, kwargs, match):
    depth, image = scene
    if kwargs.get("depth") == "nan":
        depth = depth.copy()
        depth[3, 3] = np.nan
    if kwargs.get("image") == "nan":
        image = image.copy()
        image[2, 2] = np.nan
    if kwargs.get("image") == "small":
        image = image[:-1]
    kwargs = {k: v for k, v in kwargs.items() if k not in ("depth", "image")}
    kw = {"densities": DENS, "trials": 1, "rng": 0, **kwargs}
    with pytest.raises(ValueError, match=match):
        run_sampling_study(depth, image, **kw)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_wavelet_beats_random_on_lambert_dem(seed):
    # The paper's claim (section 4.2) on a synthetic lunar plain (craters and rocks on a
    # smooth bed, 384 x 512) shaded with overhead (camera-centred) Lambert light, no shadows:
    # the wavelet strategy's eq. 4.3 MSE score over the paper's 11 densities must exceed
    # random's 1.0. Observed with these seeds and 4 trials: 1.05 and 1.41 (a thin margin for
    # seed 1: the sparsest densities, weighted most by eq. 4.3, are close to a tie). (On rough
    # fractal beds with little bare plain the score falls to ~1 at the sparsest densities,
    # which dominate eq. 4.3; the denser half of the densities favours wavelet 1.5-7x there.)
    h = lunar_dem((384, 512), np.random.default_rng(seed))
    res = run_sampling_study(
        h,
        lambert_overhead(h),
        strategies=["random", "wavelet"],
        trials=4,
        rng=seed,
        metrics=["mse"],
    )
    assert res.scores["mse"]["wavelet"] > 1.0
    me = res.mean_errors()["mse"]
    # at the densest four densities the advantage is large
    assert np.all(me["random"][:4] > 1.5 * me["wavelet"][:4])


def test_progress_and_nan_policy(scene):
    depth, image = scene
    seen = []
    with reporting(lambda ev: seen.append((ev.done, ev.total))):  # the progress channel
        res = run_sampling_study(
            depth, image, densities=DENS, trials=2, rng=0, metrics=["mse"],
            strategies=["random", "wavelet"], outside="nan",
        )  # fmt: skip
    assert seen == [(0, 12), (3, 12), (6, 12), (9, 12), (12, 12), (12, 12)]
    # NaN outside the hull is excluded, never propagated into the errors
    assert all(np.isfinite(r["value"]) for r in res.rows)
    near = run_sampling_study(
        depth, image, densities=DENS, trials=2, rng=0, metrics=["mse"],
        strategies=["random", "wavelet"],
    )  # fmt: skip
    # same samples (same seeds), only the hull policy differs: the densest level covers
    # nearly all cells, so both policies agree closely there
    a = res.errors("mse")["random"][0]
    b = near.errors("mse")["random"][0]
    np.testing.assert_allclose(a, b, rtol=0.5)
    # at the sparsest level the hull leaves cells out, so the policies do differ
    assert not np.array_equal(res.errors("mse")["random"][2], near.errors("mse")["random"][2])


def test_tables_use_registry_labels_for_variants(scene):
    # a strategy_options variant is named as in figure legends, and LaTeX gets no raw "_"
    depth, image = scene
    res = run_sampling_study(
        depth, image, densities=DENS, trials=1, rng=0, metrics=["mse"],
        strategies=["random", "wavelet_bn", "my_variant"],
        strategy_options={
            "wavelet_bn": {"strategy": "wavelet", "blue_noise": True},
            "my_variant": {"strategy": "wavelet"},
        },
    )  # fmt: skip
    md, tex = score_tables([("", res.scores)], strategies=res.strategies, metrics=res.metrics)
    md = [line for line in md.splitlines() if line.startswith("|")]
    assert md[0] == "| Metric | Random | Wavelet, blue noise | My variant |"
    assert "_" not in tex.split("\\midrule")[0].replace("\\_", "")


# --------------------------------------------------------------------------- reconstructions
def _baseline_scene():
    """The scene of tests/data/sampling_rows_linear_9e82372.json (rows of commit 9e82372,
    before reconstructions were configurable: same code, same seeds)."""
    rng = np.random.default_rng(7)
    r, c = np.mgrid[0:48, 0:40]
    depth = np.sin(r / 5.0) * np.cos(c / 7.0) + 0.02 * rng.standard_normal((48, 40))
    image = 0.5 + 0.4 * np.cos(r / 5.0) * np.cos(c / 7.0)
    o = SamplingStudyOptions(
        strategies=("random", "grid", "wavelet"), densities=(1 / 8, 1 / 32), trials=2,
        metrics=("mse", "grad", "sal"), score_region="both", range_noise_std=0.01,
    )  # fmt: skip
    return depth, image, o


def test_linear_only_rows_are_the_rows_of_before():
    import json
    from pathlib import Path

    depth, image, o = _baseline_scene()
    res = sampling.run_sampling_study(depth, image, o, rng=3)
    before = json.loads(
        (Path(__file__).parents[1] / "data" / "sampling_rows_linear_9e82372.json").read_text()
    )
    assert [r.pop("reconstruction") for r in res.rows] == ["linear"] * len(res.rows)
    assert res.rows == before["rows"]  # exact floats, same order
    assert res.scores == before["scores"]


def _register_offset():
    from dataclasses import dataclass as _dc

    from simlunar.reconstruction import RECONSTRUCTIONS, Reconstructed
    from simlunar.registry import check_bounds, option

    @_dc(frozen=True)
    class OffsetOptions:
        gain: float = option(0.0, doc="image gain", ge=0)

        def __post_init__(self):
            check_bounds(self)

    def offset(points_rc, values, shape, *, guide=None, options=None):
        base = reconstruct(points_rc, values, shape)
        return Reconstructed(base + options.gain * guide.image, {"shading_share": 0.25})

    RECONSTRUCTIONS.register("test_offset", offset, OffsetOptions, guided=True)


@pytest.fixture
def offset_recon():
    from simlunar.reconstruction import RECONSTRUCTIONS

    _register_offset()
    yield "test_offset"
    del RECONSTRUCTIONS._entries["test_offset"]


def test_every_reconstruction_gets_rows_and_its_own_errors(offset_recon):
    from simlunar.reconstruction import Guide

    depth, image, o = _baseline_scene()
    o2 = SamplingStudyOptions(
        strategies=o.strategies, densities=o.densities, trials=2, metrics=("mse",),
        reconstructions={"linear": None, offset_recon: {"gain": 0.0}},
    )  # fmt: skip
    guide = Guide(image, frames=("sun", "camera"), spacing=0.5)
    res = sampling.run_sampling_study(depth, image, o2, rng=3, guide=guide)
    assert res.reconstructions == ["linear", offset_recon]
    lin = [r for r in res.rows if r["reconstruction"] == "linear"]
    off = [r for r in res.rows if r["reconstruction"] == offset_recon]
    assert len(lin) == len(off) == 3 * 2 * 2
    assert all("guide_frames" not in r for r in lin)
    assert {(r["guide_frames"], r["exposures"]) for r in off} == {("sun+camera", 2)}
    # gain 0: the same grid from the same samples, so the same errors (paired acquisitions)
    for a, b in zip(lin, off):
        assert (a["strategy"], a["density"], a["trial"]) == (
            b["strategy"],
            b["density"],
            b["trial"],
        )
        assert a["value"] == b["value"]
    np.testing.assert_array_equal(
        res.errors("mse")["grid"], res.errors("mse", offset_recon)["grid"]
    )
    saved = res.reconstruction_saved(offset_recon)
    np.testing.assert_allclose(saved["wavelet"].summary[offset_recon], 1.0)
    assert res.info[offset_recon]["grid"]["shading_share"].shape == (2, 2)
    assert np.all(res.info[offset_recon]["grid"]["shading_share"] == 0.25)
    assert "linear" not in res.info
    with pytest.raises(ValueError, match="reconstruction 'smoothed' not in this study"):
        res.errors("mse", "smoothed")


def test_a_guide_of_another_grid_and_unknown_reconstructions_are_errors():
    from simlunar.reconstruction import Guide

    depth, image, o = _baseline_scene()
    with pytest.raises(ValueError, match=r"guide \(4, 4\) and depth"):
        sampling.run_sampling_study(depth, image, o, rng=0, guide=Guide(np.ones((4, 4))))
    with pytest.raises(ValueError, match="unknown reconstruction 'shadng'; valid: linear"):
        SamplingStudyOptions(reconstructions=("shadng",))
