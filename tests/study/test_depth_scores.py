"""Guide-view depth scores: the GRAD weights leave the holes of the truth out."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from simlunar.study.depth_scores import score_depth


def test_grad_score_ignores_the_holes_of_the_truth(rng):
    # a tilted plane (m): every GRAD weight is the same |slope|, so GRAD is the plain MSE of
    # the evaluated cells, whatever the errors
    r, c = np.mgrid[0:40, 0:50]
    truth = 1.5 + 0.01 * c + 0.004 * r
    hole = np.zeros(truth.shape, bool)
    hole[12:20, 15:30] = True
    err = rng.normal(0.0, 1e-3, truth.shape)
    err[ndimage.binary_dilation(hole, iterations=2) & ~hole] *= 20  # errors around the hole
    depth = truth + err
    with_hole = score_depth(depth, np.where(hole, np.nan, truth), metrics=("grad", "mse"))
    reference = score_depth(depth, truth, metrics=("grad", "mse"), mask=~hole)
    assert reference["grad"] == pytest.approx(reference["mse"], rel=1e-12)
    assert with_hole["grad"] == pytest.approx(reference["grad"], rel=1e-9)
    assert with_hole["mse"] == pytest.approx(reference["mse"], rel=1e-12)
