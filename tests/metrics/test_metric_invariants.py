"""Weighted metrics are weighted means: scaling the weights changes nothing, whatever they sum
to (a normalised saliency map sums to 1, a probability map to less)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics import metric


@pytest.mark.parametrize("scale", [1e-6, 0.25, 1.0, 40.0])
@pytest.mark.parametrize("name", ["sal", "grad"])
def test_weighted_metrics_do_not_depend_on_the_weights_scale(name, scale):
    rng = np.random.default_rng(3)
    truth = rng.normal(size=(6, 7))
    recon = truth + rng.normal(size=truth.shape)
    w = rng.random(truth.shape)
    w /= w.sum()  # sums to 1: a normalised map is a valid weight map
    want = float(np.sum(w * (recon - truth) ** 2))
    assert metric(name, recon, truth, weights=scale * w) == pytest.approx(want, rel=1e-12)


def test_a_single_weighted_cell_is_its_squared_error():
    truth = np.zeros((2, 2))
    recon = np.array([[0.0, 3.0], [1.0, 0.0]])
    w = np.array([[0.0, 0.5], [0.0, 0.0]])  # weights summing to 0.5
    assert metric("sal", recon, truth, weights=w) == pytest.approx(9.0)
