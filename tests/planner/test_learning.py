"""Training the learned map: the error target (log squared error of uniform layouts) where
the terrain is rough, seeded; the training inputs' checks."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.features.learned import pitch_of
from simlunar.planner.learning import error_target, train_learned_map


def _pair(shape=(24, 24)):
    r = np.random.default_rng(0)
    return np.clip(0.5 + 0.1 * r.standard_normal(shape), 0.01, None), r.standard_normal(shape)


def test_error_target_lies_on_the_rough_patch():
    z = np.zeros((64, 64))
    z[20:40, 20:40] = np.random.default_rng(2).standard_normal((20, 20))
    t = error_target(z, density=1 / 16, rng=0)
    assert t.shape == z.shape and t.dtype == np.float32
    assert t[25:35, 25:35].mean() > t[:10, :10].mean() + 5  # log units: e^5 ~ 150x


def test_training_inputs_are_validated():
    img, z = _pair()
    with pytest.raises(ValueError, match="truth"):
        train_learned_map([(img, z[:, :10])], densities=[0.1], rng=0)
    with pytest.raises(ValueError, match="distinct"):
        train_learned_map([(img, z)], densities=[0.1, 0.1], rng=0)
    with pytest.raises(ValueError, match="density"):
        pitch_of(0.0)
    with pytest.raises(ValueError, match="at least one"):
        train_learned_map([], densities=[0.1], rng=0)


def test_error_target_is_seeded():
    z = np.random.default_rng(5).standard_normal((32, 32))
    a = error_target(z, density=1 / 8, rng=3)
    np.testing.assert_array_equal(a, error_target(z, density=1 / 8, rng=3))
    assert not np.array_equal(a, error_target(z, density=1 / 8, rng=4))
    # more layouts average more: the target still lies where it did
    b = error_target(z, density=1 / 8, layouts=6, rng=3)
    assert np.corrcoef(a.ravel(), b.ravel())[0, 1] > 0.5


def test_error_target_refuses_bad_truth():
    with pytest.raises(
        ValueError, match=r"^truth must be a finite \(rows, cols\) array, got shape \(4,\)$"
    ):
        error_target(np.zeros(4), density=0.5)
    z = np.zeros((8, 8))
    z[3, 3] = np.nan
    with pytest.raises(ValueError, match=r"got shape \(8, 8\)$"):
        error_target(z, density=0.5)
