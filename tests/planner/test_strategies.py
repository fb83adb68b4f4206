"""Planners: exact k distinct pixels, reproducibility, where the samples go, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from simlunar.features import MAPS
from simlunar.planner import MEASURING, ORACLES, STRATEGIES, SamplePlan, combine_maps, plan

SHAPE = (60, 80)


def _step_image(shape=SHAPE, col=40):
    img = np.zeros(shape)
    img[:, col:] = 1.0
    return img


VARIANTS = [
    ("grid", {}),
    ("random", {}),
    *[(s, {}) for s in ("gradient", "entropy", "wavelet", "saliency")],
    ("combination", {"coefficients": {"wavelet": 1.0, "gradient": 0.5}}),
    ("wavelet", {"uniform_mix": 0.3}),
    ("wavelet", {"density_cap": 2.0, "cap_block": 8}),
    ("entropy", {"blue_noise": True}),
]


@pytest.mark.parametrize(("strategy", "opts"), VARIANTS)
@pytest.mark.parametrize("k", [3, 17, 480, 2400, SHAPE[0] * SHAPE[1]])
def test_exactly_k_distinct_in_bounds(rng, strategy, opts, k):
    img = rng.random(SHAPE) + _step_image()
    p = plan(strategy, k, image=img, rng=7, **opts)
    assert isinstance(p, SamplePlan) and p.k == k and p.shape == SHAPE
    assert np.unique(p.flat).size == k
    assert p.rows.min() >= 0 and p.rows.max() < SHAPE[0]
    assert p.cols.min() >= 0 and p.cols.max() < SHAPE[1]
    assert np.all(np.diff(p.flat) > 0)  # canonical row-major order


@pytest.mark.parametrize(("strategy", "opts"), VARIANTS)
def test_same_rng_same_plan(rng, strategy, opts):
    img = rng.random(SHAPE)
    a = plan(strategy, 300, image=img, rng=np.random.default_rng(3), **opts)
    b = plan(strategy, 300, image=img, rng=np.random.default_rng(3), **opts)
    c = plan(strategy, 300, image=img, rng=np.random.default_rng(4), **opts)
    np.testing.assert_array_equal(a.flat, b.flat)
    assert not np.array_equal(a.flat, c.flat)


@pytest.mark.parametrize(
    ("strategy", "factor"),
    [("gradient", 3.0), ("entropy", 3.0), ("wavelet", 3.0), ("saliency", 2.0)],
)
def test_weighted_planners_concentrate_on_step_edge(strategy, factor):
    # Step at column 40 of 80; band = columns 32..47 (16 of 80 columns, 20 % of the pixels),
    # so uniform sampling puts ~20 % of the samples there. Gradient, entropy and wavelet must
    # put >= 3x as many there (>= 60 %; observed 80-100 %); Itti-Koch saliency works on pyramid
    # levels 2-4 (4-16 px), so its edge response is ~ 30 px wide and holds 53 % of its mass in
    # the band: it must reach >= 2x (40 %). k = 100 is below the 120 pixels where the gradient
    # map is non-zero. Fixed seed.
    img = _step_image()
    band = lambda p: np.mean((p.cols >= 32) & (p.cols < 48))  # noqa: E731
    rand = band(plan("random", 100, shape=SHAPE, rng=11))
    weighted = band(plan(strategy, 100, image=img, rng=11))
    assert 0.12 < rand < 0.28
    assert weighted >= factor * 0.2


def _chi2_uniform(p, blocks=(4, 4)):
    counts = np.histogram2d(p.rows, p.cols, bins=blocks, range=[[0, p.shape[0]], [0, p.shape[1]]])[
        0
    ].ravel()
    return stats.chisquare(counts).pvalue


@pytest.mark.parametrize("strategy", ["gradient", "entropy", "wavelet", "saliency"])
def test_constant_image_falls_back_to_uniform(strategy):
    # 1200 samples of 4800 pixels in 4 x 4 equal blocks: a chi-square test against uniform
    # counts must not reject at the 1 % level (fixed seed); the step image is rejected hard.
    p = plan(strategy, 1200, image=np.full(SHAPE, 0.3), rng=5)
    assert _chi2_uniform(p) > 0.01
    # power check: the same test rejects the plan of the step image (k below the edge area)
    assert _chi2_uniform(plan(strategy, 100, image=_step_image(), rng=5)) < 1e-6


def test_uniform_mix_one_is_uniform():
    p = plan("gradient", 1200, image=_step_image(), rng=5, uniform_mix=1.0)
    assert _chi2_uniform(p) > 0.01


def test_density_cap_binds_and_moves_samples_off_the_edge():
    # The gradient map of the step is non-zero only on columns 39 and 40 (120 pixels). With
    # k = 100 < 120 the uncapped plan puts every sample there. Cap 2 in 10 x 10 blocks:
    # ceil(2 * 100/4800 * 100) = 5 per block; the edge columns cross 6 x 2 = 12 blocks, so at
    # most 60 samples stay on the edge and the 40 others go to zero-weight pixels.
    img = _step_image()
    k, block, cap = 100, 10, 2.0
    per_block = int(np.ceil(cap * k / img.size * block * block))
    assert per_block == 5
    on_edge = lambda p: np.mean((p.cols == 39) | (p.cols == 40))  # noqa: E731
    free = plan("gradient", k, image=img, rng=2)
    capped = plan("gradient", k, image=img, rng=2, density_cap=cap, cap_block=block)
    count = lambda p: np.bincount((p.rows // block) * 8 + p.cols // block, minlength=48)  # noqa: E731
    assert on_edge(free) == 1.0 and count(free).max() == 10  # the cap would bind
    assert capped.k == k and count(capped).max() == per_block
    # the edge pixels have the highest priority, so the 12 edge blocks fill up to the cap
    assert on_edge(capped) == pytest.approx(12 * per_block / k)


def test_density_cap_too_tight_is_an_error():
    with pytest.raises(ValueError, match="density_cap must be >= 1"):
        plan("wavelet", 100, image=_step_image(), rng=0, density_cap=0.5)


def test_blue_noise_spreads_samples():
    # Constant weights: target density rho = k / N, radius 0.5 / sqrt(rho) = 0.5 * 6.93 = 3.46 px
    from scipy.spatial import cKDTree

    k = 100
    p = plan("wavelet", k, image=np.ones(SHAPE), rng=1, blue_noise=True)
    r = plan("random", k, shape=SHAPE, rng=1)
    nn = lambda q: cKDTree(q.rc).query(q.rc, k=2)[0][:, 1]  # noqa: E731
    assert nn(p).min() >= 0.5 / np.sqrt(k / (SHAPE[0] * SHAPE[1]))
    assert nn(r).min() < 2.0
    assert nn(p).mean() > 1.2 * nn(r).mean()


def test_zero_weights_drawn_only_when_needed(rng):
    w = np.zeros(SHAPE)
    hot = rng.choice(w.size, 10, replace=False)
    w.ravel()[hot] = rng.random(10) + 0.1
    p = plan("wavelet", 25, weights=w, rng=3)
    assert set(hot) <= set(p.flat.tolist())
    p = plan("wavelet", 5, weights=w, rng=3)
    assert set(p.flat.tolist()) <= set(hot)


def test_weighted_sampling_follows_weights():
    # Two halves with weight ratio 3:1, k small relative to N: expected share 0.75 of the
    # samples in the heavy half; 2000 of 4800 without replacement shifts it slightly towards
    # 0.5 (the heavy half depletes), so accept 0.68..0.76 (fixed seed).
    w = np.ones(SHAPE)
    w[:, :40] = 3.0
    p = plan("gradient", 600, weights=w, rng=9)
    share = np.mean(p.cols < 40)
    assert 0.68 < share < 0.78


def test_grid_hand_computed():
    # 10 x 10 grid, k = 25: a 5 x 5 lattice of pitch 2, shifted by a random offset in [0, 2).
    p = plan("grid", 25, shape=(10, 10), rng=0)
    rows, cols = np.unique(p.rows), np.unique(p.cols)
    assert rows.size == 5 and cols.size == 5
    np.testing.assert_array_equal(np.diff(rows), 2)
    np.testing.assert_array_equal(np.diff(cols), 2)
    # k = 23: the same lattice minus two points
    assert plan("grid", 23, shape=(10, 10), rng=0).k == 23


def test_grid_shift_is_rigid_and_uniform_over_one_pitch():
    # 60 x 80, k = 50: a 6 x 9 lattice (54 points, 4 dropped at random), row pitch 60/6 = 10:
    # rows = floor(off + 10 i) with off ~ U(0, 10), so every plan's rows are one lattice shifted
    # as a whole and the first row is uniform on 0..9 across seeds.
    first = []
    for s in range(400):
        rows = np.unique(plan("grid", 50, shape=SHAPE, rng=s).rows)
        assert rows.size == 6
        np.testing.assert_array_equal(np.diff(rows), 10)
        first.append(rows[0])
    counts = np.bincount(first)
    assert counts.size == 10  # never shifted by a pitch or more
    assert stats.chisquare(counts).pvalue > 0.01  # 40 expected per offset (fixed seeds)


def test_combination_is_normalised_sum():
    a, b = np.full((2, 2), 2.0), np.array([[1.0, 3.0], [0.0, 0.0]])
    np.testing.assert_allclose(
        combine_maps({"gradient": a, "wavelet": b}, {"gradient": 1.0, "wavelet": -0.5}),
        1.0 + 0.5 * np.array([[1.0, 3.0], [0.0, 0.0]]),
    )


def test_sample_plan_validation():
    with pytest.raises(ValueError, match="distinct"):
        SamplePlan([0, 0], [1, 1], (3, 3))
    with pytest.raises(ValueError, match="outside"):
        SamplePlan([0, 3], [1, 1], (3, 3))
    p = SamplePlan([2, 0], [1, 2], (3, 3))
    np.testing.assert_array_equal(p.flat, [7, 2])
    np.testing.assert_array_equal(p.rc, [[2, 1], [0, 2]])
    assert p.mask().sum() == 2
    with pytest.raises(ValueError):
        p.rows[0] = 1


@pytest.mark.parametrize(
    ("args", "kwargs", "match"),
    [
        (("random", 2), {"shape": SHAPE}, "k must be >= 3"),
        (("random", 4801), {"shape": SHAPE}, "exceeds the number of pixels N = 4800"),
        (("random", 10.5), {"shape": SHAPE}, "k must be an integer"),
        (("sobel", 10), {"shape": SHAPE}, "unknown strategy 'sobel'; valid: grid, random"),
        (("random", 10), {"shape": SHAPE, "blue_noise": True}, "unknown option"),
        (("wavelet", 10), {"image": np.full(SHAPE, np.nan)}, "NaN"),
        (("wavelet", 10), {"weights": -np.ones(SHAPE)}, "weights must be finite and >= 0"),
        (("wavelet", 10), {"image": np.ones(SHAPE), "weights": np.ones((5, 5))}, "mismatched"),
        (("wavelet", 10), {"shape": SHAPE}, "needs image= or weights="),
        (("random", 10), {}, "needs one of image, weights or shape"),
        (("wavelet", 10), {"image": np.ones(SHAPE), "uniform_mix": 2.0}, "uniform_mix"),
        (("combination", 10), {"image": np.ones(SHAPE)}, "needs coefficients"),
    ],
)
def test_bad_input(args, kwargs, match):
    with pytest.raises(ValueError, match=match):
        plan(*args, rng=0, **kwargs)


def test_registry_names():
    assert set(STRATEGIES) == {
        "grid", "random", *MAPS, "combination", "wavelet_lloyd", "log_lloyd", "lloyd_uniform", *ORACLES,
        *MEASURING,
    }  # fmt: skip
