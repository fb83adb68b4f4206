"""Interior-only scoring: the border band mask and the sparsest pitch."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics import interior_mask, metric, sparsest_pitch


def test_interior_mask_hand_case():
    # 5 x 6 grid, pitch 1: distance to the border min(r, c, 4 - r, 5 - c) > 1 leaves
    # row 2, cols 2-3
    m = interior_mask((5, 6), 1.0)
    expected = np.zeros((5, 6), dtype=bool)
    expected[2, 2:4] = True
    np.testing.assert_array_equal(m, expected)
    assert interior_mask((5, 6), 0.0).sum() == 3 * 4


def test_sparsest_pitch():
    assert sparsest_pitch((100, 100), [1 / 4, 1 / 16, 1 / 2]) == pytest.approx(4.0)
    assert sparsest_pitch((10, 10), [1.0]) == pytest.approx(1.0)


def test_metric_with_interior_mask_ignores_the_border_band():
    truth = np.zeros((20, 30))
    recon = truth.copy()
    recon[:3, :] = 10.0  # extrapolation error in the top band only
    recon[10, 15] = 2.0  # one interior error
    mask = interior_mask(truth.shape, 3.0)
    assert metric("mse", recon, truth, mask=mask) == pytest.approx(4.0 / mask.sum())
    assert metric("mse", recon, truth) > 10.0


@pytest.mark.parametrize(
    ("shape", "pitch", "match"),
    [((5, 6), 2.0, "no interior"), ((5, 6), -1.0, "pitch"), ((0, 6), 1.0, "shape")],
)
def test_interior_mask_bad_input(shape, pitch, match):
    with pytest.raises(ValueError, match=match):
        interior_mask(shape, pitch)


def test_sparsest_pitch_bad_density():
    with pytest.raises(ValueError):
        sparsest_pitch((10, 10), [0.0])


def test_a_one_row_grid_is_a_valid_shape_with_no_interior():
    """(1, 5) is a grid (rows >= 1): its every cell is on the border, so no pitch leaves an
    interior, and the error says so (not that the shape is invalid)."""
    from simlunar.metrics.interior import interior_mask

    with pytest.raises(ValueError, match="leaves no interior cell in a 1 x 5 grid"):
        interior_mask((1, 5), 0.0)
    with pytest.raises(ValueError, match=r"shape must be \(rows, cols\) >= 1"):
        interior_mask((0, 5), 0.0)
    np.testing.assert_array_equal(interior_mask((3, 3), 0.0), [[0, 0, 0], [0, 1, 0], [0, 0, 0]])


def test_a_one_column_grid_is_a_valid_shape_with_no_interior():
    """(5, 1) is a grid too (cols >= 1): no interior, and the error says so."""
    with pytest.raises(ValueError, match="leaves no interior cell in a 5 x 1 grid"):
        interior_mask((5, 1), 0.0)
