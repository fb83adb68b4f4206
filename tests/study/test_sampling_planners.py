"""The sampling study's planner adapter: oracles get the truth and nothing else does,
multi-round planning reads the scene through the sensor only, interior-only scores."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics.interior import interior_mask, sparsest_pitch
from simlunar.planner import SequentialOptions
from simlunar.sensors.base import Acquisition
from simlunar.sensors.ideal import IdealSampler
from simlunar.study import sampling_planners
from simlunar.study.sampling import SamplingStudyOptions, run_sampling_study


def _scene(rows=48, cols=64):
    y, x = np.mgrid[0:rows, 0:cols] / 16.0
    depth = np.sin(3 * x) * np.cos(2 * y) + 0.5 * np.exp(-((x - 2) ** 2 + (y - 1.5) ** 2) * 8)
    image = (0.5 + 0.4 * np.sin(3 * x + 1) * np.cos(2 * y)).astype(np.float32)
    return depth, image


def test_only_oracle_labels_are_given_the_truth():
    depth, image = _scene()
    o = SamplingStudyOptions(
        strategies=["random", "wavelet", "lloyd_uniform", "wl", "oracle_greedy", "oracle_h", "sequential"],
        strategy_options={"wl": {"strategy": "wavelet", "placement": "lloyd"},
                          "oracle_h": {"strategy": "oracle_hessian"}},
        densities=[1 / 16], trials=1,
    )  # fmt: skip
    planners, _ = sampling_planners.study_planners(o, image, depth, [192])
    assert planners["oracle_greedy"].truth is depth and planners["oracle_h"].truth is depth
    for label in ("random", "wavelet", "lloyd_uniform", "wl"):
        assert planners[label].truth is None
    assert not hasattr(planners["sequential"], "truth")  # it is given the sensor, not the depth


class _Recorder:
    """An ideal sensor that records every cell it is asked to measure."""

    name = "recorder"
    needs_plan = True

    def __init__(self, depth):
        self.inner = IdealSampler(depth)
        self.asked: list[np.ndarray] = []

    def acquire(self, rc, *, rng=None) -> Acquisition:
        self.asked.append(np.asarray(rc).copy())
        return self.inner.acquire(rc, rng=rng)


def test_multi_round_reads_the_scene_only_at_the_cells_it_samples():
    depth, image = _scene()
    planner = sampling_planners.measuring_planner(
        {"sequential": SequentialOptions(max_rounds=5), "prior": "wavelet", "feature_opts": {}},
        image, depth.shape, [150], {},
    )  # fmt: skip
    sensor = _Recorder(depth)
    acq, rounds = planner.acquire(150, sensor, 1, 2)
    asked = np.concatenate(sensor.asked)
    assert rounds == len(sensor.asked) and 2 <= rounds <= 5
    flat = asked[:, 0] * depth.shape[1] + asked[:, 1]
    assert len(flat) == len(np.unique(flat)) == 150  # each cell read once, k cells in all
    got = np.asarray(acq.rc, dtype=np.int64)
    assert set(got[:, 0] * depth.shape[1] + got[:, 1]) == set(flat)
    assert np.array_equal(acq.values, depth[got[:, 0], got[:, 1]])


def test_study_reports_rounds_and_interior_scores():
    depth, image = _scene()
    o = SamplingStudyOptions(
        strategies=["random", "lloyd_uniform", "sequential", "oracle_greedy"],
        strategy_options={"sequential": {"sequential": SequentialOptions(max_rounds=4),
                                         "prior": None}},
        densities=[1 / 8, 1 / 32], trials=2, metrics=["mse"], score_region="both",
    )  # fmt: skip
    res = run_sampling_study(depth, image, o, rng=0)
    assert res.metrics == ["mse", "mse_interior"]
    assert set(res.rounds) == {"sequential"}
    assert res.rounds["sequential"].shape == (2, 2) and (res.rounds["sequential"] >= 2).all()
    full, inner = res.errors("mse"), res.errors("mse_interior")
    # the interior leaves out the border band where a reconstruction extrapolates
    mask = interior_mask(depth.shape, sparsest_pitch(depth.shape, [1 / 8, 1 / 32]))
    assert 0 < mask.sum() < depth.size
    assert not np.allclose(full["random"], inner["random"])
    # the oracle reads the truth: it beats the image-free layout on this smooth scene
    assert full["oracle_greedy"].mean() < full["lloyd_uniform"].mean()


def test_unknown_score_region_is_refused():
    with pytest.raises(ValueError, match="score_region"):
        SamplingStudyOptions(score_region="edges")


def _oracle_study(seed, densities=(1 / 32, 1 / 64)):
    from simlunar.reconstruction import Guide
    from simlunar.reconstruction.synthetic import lit_terrain

    t = lit_terrain((96, 128), rng=seed)
    o = SamplingStudyOptions(
        strategies=["oracle_greedy", "oracle_shading"],
        strategy_options={"oracle_shading": {"strategy": "oracle_greedy",
                                             "reconstruction": "shading"}},
        densities=list(densities), trials=1, metrics=["mse"],
        reconstructions=["linear", "shading"],
    )  # fmt: skip
    guide = Guide(t.image, light=t.light)
    return t, o, guide, run_sampling_study(t.heights, t.image, o, rng=0, guide=guide)


def test_an_oracle_of_a_reconstruction_is_fed_that_reconstructions_error():
    from simlunar.planner import oracle_greedy
    from simlunar.reconstruction import run_reconstruction

    t, o, guide, _ = _oracle_study(0, densities=(1 / 32,))
    k = round(t.heights.size / 32)
    planners, _ = sampling_planners.study_planners(o, t.image, t.heights, [k], guide=guide)
    assert planners["oracle_greedy"].reconstruct is None  # linear: the oracle's own
    fed = planners["oracle_shading"].reconstruct
    assert fed.name == "shading" and fed.guide is guide
    want = oracle_greedy(
        t.heights, k,
        reconstruct=lambda rc, v: run_reconstruction(
            "shading", rc, v, t.heights.shape, guide=guide).heights,
    )  # fmt: skip
    got = planners["oracle_shading"](k, 0)
    np.testing.assert_array_equal(np.sort(got[:, 0] * 128 + got[:, 1]), want)


def test_each_oracle_is_the_better_bound_under_its_own_reconstruction():
    # synthetic Lambert terrain (constant albedo, 30 deg sun), 96 x 128 cells, densities 1/32
    # and 1/64, 3 terrains. Measured MSE ratios: under shading, oracle(shading) over
    # oracle(linear) 0.88-1.00 (geometric mean 0.91); under linear, oracle(linear) over
    # oracle(shading) 0.69-0.96 (0.80)
    under_shading, under_linear = [], []
    for seed in range(3):
        *_, res = _oracle_study(seed)
        sh, li = res.errors("mse", "shading"), res.errors("mse", "linear")
        under_shading += list(np.log(sh["oracle_shading"] / sh["oracle_greedy"]).ravel())
        under_linear += list(np.log(li["oracle_greedy"] / li["oracle_shading"]).ravel())
    assert np.exp(np.mean(under_shading)) < 0.96
    assert np.exp(np.mean(under_linear)) < 0.9


def test_an_oracle_of_a_reconstruction_not_in_the_study_is_refused():
    depth, image = _scene()
    o = SamplingStudyOptions(
        strategies=["oracle_x"], densities=[1 / 16], trials=1,
        strategy_options={"oracle_x": {"strategy": "oracle_greedy", "reconstruction": "shading"}},
    )  # fmt: skip
    with pytest.raises(ValueError, match="not one of the study's reconstructions"):
        sampling_planners.study_planners(o, image, depth, [192])
