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
