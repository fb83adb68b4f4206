"""Oracle planners: exact k, labelled, need the truth, and beat every realisable layout."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from simlunar.metrics import metric
from simlunar.planner import (
    ORACLES,
    STRATEGY_NAMES,
    OracleGreedyOptions,
    framed_grid,
    oracle_greedy,
    plan,
)
from simlunar.reconstruction import reconstruct

SHAPE = (96, 128)


def _patch_terrain():
    """A tilted plane (linear reconstruction is exact there) with one smooth rough patch.

    The answer is known: every sample beyond those that pin the plane belongs in the 32 x 32
    patch (rows 30-61, cols 70-101), rough at a 2.5 px scale (Gaussian-filtered noise). The
    guide image is that shading times an albedo textured everywhere (as regolith is), so the
    image does not single out the patch: only a planner that reads the depth can know it.
    """
    rr, cc = np.mgrid[0 : SHAPE[0], 0 : SHAPE[1]].astype(float)
    patch = (rr >= 30) & (rr < 62) & (cc >= 70) & (cc < 102)
    rough = ndimage.gaussian_filter(np.random.default_rng(0).standard_normal(SHAPE), 2.5)
    depth = 0.01 * rr - 0.02 * cc + 5.0 + 2.0 * patch * rough / rough[patch].std()
    gy, gx = np.gradient(depth)
    albedo = 0.5 + ndimage.gaussian_filter(np.random.default_rng(1).random(SHAPE), 1.5)
    return depth, albedo / np.sqrt(1.0 + gx**2 + gy**2)  # a Lambert-like overhead image


def _mse(p, depth):
    return metric("mse", reconstruct(p.rc, depth[p.rows, p.cols], depth.shape), depth)


def test_greedy_oracle_beats_every_realisable_strategy():
    # k = 400 (1/31 of the cells), 3 seeds each. Observed MSE: greedy oracle 0.035, Hessian
    # oracle 0.016-0.018, the best realisable (wavelet / gradient + lloyd placement)
    # 0.089-0.112, weighted random wavelet 0.096-0.155, grid / random / lloyd_uniform 0.12-0.22.
    depth, image = _patch_terrain()
    k = 400
    realisable = [
        ("grid", {}),
        ("random", {}),
        ("lloyd_uniform", {}),
        ("wavelet", {}),
        ("wavelet", {"placement": "lloyd"}),
        ("gradient", {"placement": "lloyd"}),
    ]
    best = min(
        _mse(plan(s, k, image=image, rng=seed, **o), depth)
        for s, o in realisable
        for seed in range(3)
    )
    for oracle in ORACLES:
        worst = max(_mse(plan(oracle, k, truth=depth, rng=seed), depth) for seed in range(3))
        assert worst < 0.8 * best, oracle


def test_oracles_labelled_and_named():
    for name in ORACLES:
        assert name.startswith("oracle_")
        assert STRATEGY_NAMES[name].startswith("Oracle")


@pytest.mark.parametrize("oracle", ORACLES)
@pytest.mark.parametrize("k", [4, 5, 37, 1000, SHAPE[0] * SHAPE[1]])
def test_oracle_exactly_k_distinct_and_reproducible(oracle, k):
    depth, _ = _patch_terrain()
    p = plan(oracle, k, truth=depth, rng=3)
    assert p.k == k and np.unique(p.flat).size == k and p.shape == SHAPE
    np.testing.assert_array_equal(p.flat, plan(oracle, k, truth=depth, rng=3).flat)


def test_greedy_oracle_on_flat_terrain_fills_holes():
    # zero error everywhere: the batches go to the largest holes, so the layout stays even
    flat = oracle_greedy(np.zeros((40, 60)), 120)
    r, c = np.divmod(flat, 60)
    counts = np.histogram2d(r, c, bins=(2, 3), range=[[0, 40], [0, 60]])[0]
    assert flat.size == 120 and counts.min() >= 12


def test_framed_grid_covers_border_and_corners():
    flat = framed_grid((50, 70), 100)
    r, c = np.divmod(flat, 70)
    assert flat.size <= 100 and np.unique(flat).size == flat.size
    assert {0, 69, 49 * 70, 49 * 70 + 69} <= set(flat.tolist())
    assert set(np.unique(r)) >= {0, 49} and set(np.unique(c)) >= {0, 69}


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"shape": SHAPE}, "needs truth="),
        ({"truth": np.zeros((10, 10)), "shape": SHAPE}, "mismatched grid shapes"),
        ({"truth": np.full(SHAPE, np.nan)}, "NaN"),
        ({"truth": np.zeros(SHAPE), "smooth_pitch": -1.0}, "smooth_pitch must be >= 0"),
        ({"truth": np.zeros(SHAPE), "placement": "lloyd"}, "unknown option"),
    ],
)
def test_oracle_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        plan("oracle_greedy", 50, rng=0, **kwargs)


def test_realisable_strategies_ignore_truth():
    # passing the truth to a realisable strategy changes nothing: only oracle_* read it
    depth, image = _patch_terrain()
    a = plan("wavelet", 300, image=image, rng=1, placement="lloyd")
    b = plan("wavelet", 300, image=image, truth=depth, rng=1, placement="lloyd")
    np.testing.assert_array_equal(a.flat, b.flat)


def test_greedy_oracle_reads_the_error_of_the_reconstruction_it_is_given():
    # a "reconstruction" exact on the left half (cols < 64) and linear elsewhere: every sample
    # the refiner adds beyond its framed grid goes where that reconstruction errs, the right
    # half; with linear's error (the default) both halves get samples
    rr, cc = np.mgrid[0 : SHAPE[0], 0 : SHAPE[1]].astype(float)
    rough = ndimage.gaussian_filter(np.random.default_rng(2).standard_normal(SHAPE), 2.0)
    depth = rough / rough.std() + 0.01 * rr
    left = cc < 64

    def half_exact(rc, values):
        return np.where(left, depth, reconstruct(rc, values, SHAPE))

    k, opts = 600, OracleGreedyOptions(start_share=0.25)
    grid = set(framed_grid(SHAPE, int(opts.start_share * k)).tolist())
    fed = oracle_greedy(depth, k, options=opts, reconstruct=half_exact)
    added = np.array(sorted(set(fed.tolist()) - grid))
    assert len(fed) == k and len(added) == k - len(grid)
    assert np.all(added % SHAPE[1] >= 64)
    plain = oracle_greedy(depth, k, options=opts)
    assert np.mean(plain % SHAPE[1] < 64) > 0.3
    # linear passed explicitly is the default, exactly
    np.testing.assert_array_equal(
        oracle_greedy(depth, k, options=opts, reconstruct=lambda rc, v: reconstruct(rc, v, SHAPE)),
        plain,
    )
    np.testing.assert_array_equal(
        plan("oracle_greedy", k, truth=depth, rng=0, start_share=opts.start_share,
             oracle_reconstruct=half_exact).flat,
        fed,
    )  # fmt: skip


def test_oracle_reconstruction_errors_are_clear():
    depth, _ = _patch_terrain()
    with pytest.raises(ValueError, match="returned shape"):
        oracle_greedy(depth, 50, reconstruct=lambda rc, v: np.zeros((3, 3)))
    with pytest.raises(ValueError, match="oracle_greedy only"):
        plan("oracle_hessian", 50, truth=depth, rng=0, oracle_reconstruct=lambda rc, v: depth)
