"""GroundTruth: one (rows, cols) shape for its arrays, read-only, heights from positions."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry.types import GroundTruth


def _truth(rows=2, cols=3):
    depth = np.arange(rows * cols, dtype=np.float64).reshape(rows, cols)
    position = np.stack([depth, -depth, 10.0 + depth], axis=-1)
    normal = np.zeros((rows, cols, 3), np.float32)
    normal[..., 2] = 1
    valid = np.ones((rows, cols), bool)
    return depth, position, normal, valid


def test_shape_and_heights():
    depth, position, normal, valid = _truth()
    gt = GroundTruth(depth, position, normal, valid)
    assert gt.shape == (2, 3)
    np.testing.assert_array_equal(gt.heights, 10.0 + depth)


def test_arrays_are_read_only():
    gt = GroundTruth(*_truth())
    for name in ("depth", "position", "normal", "valid"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(gt, name)[0, 0] = 0


def test_lists_become_arrays():
    gt = GroundTruth([[1.0]], [[[0.0, 0.0, 2.0]]], [[[0.0, 0.0, 1.0]]], [[True]])
    assert isinstance(gt.depth, np.ndarray) and gt.heights.tolist() == [[2.0]]


@pytest.mark.parametrize("bad", ["position", "valid"])
def test_mismatched_shapes_are_refused(bad):
    depth, position, normal, valid = _truth()
    if bad == "position":
        position = position[:, :2]
    else:
        valid = valid.T
    with pytest.raises(
        ValueError, match=r"^GroundTruth arrays must share one \(rows, cols\) shape$"
    ):
        GroundTruth(depth, position, normal, valid)
