"""Region-based iterative enhancement: reads, budget, rounds, and a gain where it must gain."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from simlunar.planner.placement import density_from_map, place
from simlunar.planner.sequential import (
    FIRST_ROUND_MIX,
    SequentialOptions,
    error_estimate,
    loo_residuals,
    plan_sequential,
    uniform_layout,
)
from simlunar.reconstruction import reconstruct


class GuardedTruth:
    """A depth grid that can only be read through :meth:`measure`, which records every read.

    Any other access (indexing, conversion to an array, iteration, arithmetic) raises.
    """

    def __init__(self, depth):
        self.__depth = np.array(depth, dtype=np.float64)
        self.reads: list[tuple[int, int]] = []
        self.calls = 0

    def measure(self, rc):
        rc = np.asarray(rc)
        assert rc.ndim == 2 and rc.shape[1] == 2
        self.calls += 1
        self.reads.extend(map(tuple, rc.tolist()))
        return self.__depth[rc[:, 0], rc[:, 1]].copy()

    def _refuse(self, *args, **kwargs):
        raise AssertionError("the planner read the truth outside measure()")

    __getitem__ = __array__ = __iter__ = __len__ = __float__ = _refuse
    __add__ = __mul__ = __sub__ = __truediv__ = _refuse


def rough_patch(seed: int, shape=(96, 144)):
    """A gentle quadratic surface with one rough disc at a random place."""
    r = np.random.default_rng(seed)
    y, x = np.mgrid[0 : shape[0], 0 : shape[1]].astype(float)
    z = 0.002 * (x - shape[1] / 2) ** 2 / shape[1] + 0.01 * y
    cy, cx = r.uniform(0.25, 0.75) * shape[0], r.uniform(0.25, 0.75) * shape[1]
    disc = np.exp(-((((y - cy) ** 2 + (x - cx) ** 2) / (2 * 14**2)) ** 3))
    return z + disc * 8 * ndimage.gaussian_filter(r.standard_normal(shape), 1.5)


def mse(flat_or_rc, values, truth):
    return float(np.mean((reconstruct(flat_or_rc, values, truth.shape) - truth) ** 2))


def test_reads_the_truth_only_at_the_cells_it_samples():
    depth = rough_patch(0)
    truth = GuardedTruth(depth)
    k = depth.size // 40
    sp = plan_sequential(k, shape=depth.shape, measure=truth.measure, rng=0)
    sampled = set(map(tuple, sp.plan.rc.tolist()))
    assert len(truth.reads) == k  # every cell read once, nothing else read
    assert set(truth.reads) == sampled
    assert truth.calls == sp.rounds
    np.testing.assert_array_equal(sp.values, depth[sp.plan.rows, sp.plan.cols])
    with pytest.raises(AssertionError, match="outside measure"):
        np.asarray(truth)


@pytest.mark.parametrize(
    ("shape", "k", "options"),
    [
        ((96, 144), 300, SequentialOptions()),
        ((50, 70), 3, SequentialOptions()),
        ((50, 70), 3500, SequentialOptions(first_share=0.5, batch_share=0.1)),
        ((40, 60), 200, SequentialOptions(max_rounds=2)),
        ((40, 60), 500, SequentialOptions(first_share=0.9, batch_share=1.0)),
        ((33, 47), 157, SequentialOptions(batch_share=0.01, max_rounds=5)),
    ],
)
def test_spends_exactly_k_distinct_samples(shape, k, options):
    depth = rough_patch(1, shape)
    sp = plan_sequential(
        k, shape=shape, measure=lambda rc: depth[rc[:, 0], rc[:, 1]], options=options, rng=3
    )
    assert sp.plan.k == k and len(np.unique(sp.plan.flat)) == k
    assert sum(sp.round_sizes) == k and len(sp.round_sizes) == sp.rounds
    assert 1 <= sp.rounds <= options.max_rounds
    assert sp.round_sizes[0] == max(3, min(k, round(options.first_share * k)))


def test_rounds_follow_the_schedule():
    depth = rough_patch(2)
    k = 1000
    sp = plan_sequential(k, shape=depth.shape, measure=lambda rc: depth[tuple(rc.T)], rng=0)
    # 300 first, then ceil(0.12 k) = 120 per round: 5 full batches and a last one of 100
    assert sp.round_sizes == (300, 120, 120, 120, 120, 120, 100)
    assert sp.rounds == 7
    capped = plan_sequential(
        k,
        shape=depth.shape,
        measure=lambda rc: depth[tuple(rc.T)],
        options=SequentialOptions(max_rounds=3),
        rng=0,
    )
    assert capped.round_sizes == (300, 120, 580)


def test_beats_a_uniform_layout_on_a_localised_rough_patch():
    ratios = []
    for seed in range(5):
        depth = rough_patch(seed)
        k = depth.size // 32
        sp = plan_sequential(k, shape=depth.shape, measure=GuardedTruth(depth).measure, rng=seed)
        r, c = np.divmod(uniform_layout(depth.shape, k, rng=seed), depth.shape[1])
        uniform = mse(np.column_stack((r, c)), depth[r, c], depth)
        ratios.append(mse(sp.plan.rc, sp.values, depth) / uniform)
    # measured 0.39-0.63 of the uniform Lloyd layout's MSE (seeds 0-4)
    assert max(ratios) < 0.8 and np.mean(ratios) < 0.6, ratios


def test_more_samples_go_to_the_rough_patch():
    depth = rough_patch(3)
    smooth = rough_patch(3) - depth  # zeros
    k = depth.size // 32
    sp = plan_sequential(k, shape=depth.shape, measure=lambda rc: depth[tuple(rc.T)], rng=0)
    flat = plan_sequential(
        k, shape=depth.shape, measure=lambda rc: smooth[tuple(rc.T)] + 1.0, rng=0
    )
    rough = np.abs(depth - ndimage.gaussian_filter(depth, 3)) > 0.5
    near = ndimage.binary_dilation(rough, iterations=5)
    assert sp.plan.mask()[near].sum() > 1.5 * flat.plan.mask()[near].sum()


def test_loo_residual_of_a_bump_on_a_plane():
    # a lattice on the plane z = 1 + 2 r - c, one sample raised by 3: its residual is 3; its
    # neighbours see a plane fit that is pulled up by 3 / (number of neighbours) at most
    r, c = np.mgrid[0:5, 0:5]
    pts = np.column_stack((r.ravel(), c.ravel())).astype(float)
    z = 1 + 2 * pts[:, 0] - pts[:, 1]
    np.testing.assert_allclose(loo_residuals(pts, z), 0.0, atol=1e-9)
    z[12] += 3.0  # the centre (2, 2)
    res = loo_residuals(pts, z)
    assert res[12] == pytest.approx(3.0)
    assert np.all(np.abs(np.delete(res, 12)) < 3.0)


def test_error_estimate_is_uniform_on_a_plane_and_takes_the_prior():
    shape = (30, 40)
    flat = uniform_layout(shape, 60, rng=0)
    rc = np.column_stack(np.divmod(flat, shape[1]))
    z = 0.5 * rc[:, 0] + rc[:, 1]
    a = error_estimate(rc, z, shape)
    np.testing.assert_allclose(a, 1.0)
    prior = np.ones(shape)
    prior[:, :20] = 4.0
    b = error_estimate(rc, z, shape, prior=prior, options=SequentialOptions(prior_power=0.5))
    np.testing.assert_allclose(b[:, :20] / b[:, 20:].mean(), 2.0)


def test_uniform_layout_is_exact_and_covers_the_corners():
    flat = uniform_layout((50, 80), 123, rng=1)
    assert flat.size == 123 and np.unique(flat).size == 123
    assert {0, 79, 49 * 80, 50 * 80 - 1} <= set(flat.tolist())


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"max_rounds": 1}, "max_rounds must be >= 2, got 1"),
        ({"max_rounds": 2.0}, "max_rounds must be an integer, got 2.0"),
        ({"first_share": 1.0}, "first_share must be < 1, got 1.0"),
        ({"batch_share": 0.0}, "batch_share must be > 0, got 0.0"),
        ({"temper": 1.5}, "temper must be <= 1, got 1.5"),
        ({"uniform_mix": -0.1}, "uniform_mix must be >= 0, got -0.1"),
        ({"prior_power": 0}, "prior_power must be > 0, got 0"),
        ({"nms_pitches": 0}, "nms_pitches must be > 0, got 0"),
        ({"nms_pitches": float("inf")}, "nms_pitches must be a finite number, got inf"),
        ({"first_round": "grid"}, "first_round must be one of 'uniform', 'prior', got 'grid'"),
    ],
)
def test_options_are_validated(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SequentialOptions(**kwargs)


def test_bad_inputs_are_refused():
    depth = rough_patch(0, (30, 40))

    def measure(rc):
        return depth[tuple(rc.T)]

    with pytest.raises(ValueError, match="measure returned shape"):
        plan_sequential(50, shape=depth.shape, measure=lambda rc: np.zeros(2), rng=0)
    with pytest.raises(ValueError, match="NaN"):
        plan_sequential(50, shape=depth.shape, measure=lambda rc: np.full(len(rc), np.nan), rng=0)
    with pytest.raises(ValueError, match="prior"):
        plan_sequential(50, shape=depth.shape, measure=measure, prior=np.ones((3, 3)), rng=0)
    with pytest.raises(ValueError, match="k = "):
        plan_sequential(5000, shape=depth.shape, measure=measure, rng=0)
    with pytest.raises(ValueError, match="SequentialOptions"):
        plan_sequential(50, shape=depth.shape, measure=measure, options={"temper": 1}, rng=0)


def test_a_prior_first_round_is_the_prior_maps_lloyd_layout():
    depth = rough_patch(4)
    cc = np.mgrid[0 : depth.shape[0], 0 : depth.shape[1]][1]
    prior = np.where(cc < depth.shape[1] // 2, 16.0, 1.0)  # the left half 16x as important
    k = depth.size // 32
    opt = SequentialOptions(first_round="prior", first_share=0.6)
    truth = GuardedTruth(depth)
    sp = plan_sequential(k, shape=depth.shape, measure=truth.measure, prior=prior, options=opt,
                         rng=9)  # fmt: skip
    first = sp.plan.flat[sp.round_of == 0]
    assert first.size == round(0.6 * k)
    want = place(
        density_from_map(prior, power=opt.prior_power, mix=FIRST_ROUND_MIX), first.size,
        rng=np.random.default_rng(9),
    )  # fmt: skip
    np.testing.assert_array_equal(np.sort(first), np.sort(want))
    # density ~ prior^(1/2) mixed 25 % uniform: (0.75 * 4/5 + 0.125) / (0.75 * 1/5 + 0.125)
    left = np.count_nonzero(first % depth.shape[1] < depth.shape[1] // 2)
    assert 2.2 < left / (first.size - left) < 3.0
    uniform = plan_sequential(k, shape=depth.shape, measure=truth.measure, prior=prior, rng=9)
    u_first = uniform.plan.flat[uniform.round_of == 0]
    u_left = np.count_nonzero(u_first % depth.shape[1] < depth.shape[1] // 2)
    assert 0.9 < u_left / (u_first.size - u_left) < 1.1
    with pytest.raises(ValueError, match="needs a prior"):
        plan_sequential(k, shape=depth.shape, measure=truth.measure, options=opt, rng=0)


def test_missing_skip_takes_a_lost_cell_but_leaves_it_out_of_the_estimate():
    # a LIDAR beam without a return: the cell is spent (never asked again), its NaN does not
    # reach the error estimate (which reads the measured cells only)
    depth = rough_patch(2, (30, 40))
    first = {}

    def lossy(rc):
        v = depth[tuple(rc.T)].copy()
        if not first:  # the first round loses its first 4 cells
            first["rc"] = rc.copy()
            v[:4] = np.nan
        return v

    sp = plan_sequential(80, shape=depth.shape, measure=lossy, rng=3, missing="skip")
    assert len(sp.plan.flat) == 80 and len(np.unique(sp.plan.flat)) == 80
    assert int(np.isnan(sp.values).sum()) == 4
    lost = {tuple(x) for x in first["rc"][:4].tolist()}
    got = {tuple(x) for x in sp.plan.rc[np.isnan(sp.values)].astype(int).tolist()}
    assert got == lost
    first.clear()
    with pytest.raises(ValueError, match="NaN"):
        plan_sequential(80, shape=depth.shape, measure=lossy, rng=3)
    with pytest.raises(ValueError, match="need 3"):
        plan_sequential(80, shape=depth.shape, measure=lambda rc: np.full(len(rc), np.nan),
                        rng=0, missing="skip")  # fmt: skip
    with pytest.raises(ValueError, match="missing must be"):
        plan_sequential(80, shape=depth.shape, measure=lossy, rng=0, missing="zero")
