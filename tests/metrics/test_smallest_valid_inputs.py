"""The smallest inputs the metrics accept are accepted, and the first ones below refused: two
sample counts for the equal-error ratio, a one-cell grid for the sparsest pitch."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics.interior import sparsest_pitch
from simlunar.metrics.score import samples_for_equal_error


def test_two_sample_counts_are_enough_for_the_equal_error_ratio():
    """One log-log segment: e_random = 100 / k and e_s = 50 / k at k = 100, 400. e_random(400)
    = 0.25 lies on the strategy's segment at k = 200 (50 / 200), so the ratio is 200 / 400 =
    0.5; e_random(100) = 1 is above the strategy's largest error 0.5 (NaN, no extrapolation)."""
    out = samples_for_equal_error({"random": [1.0, 0.25], "s": [0.5, 0.125]}, [100, 400])
    np.testing.assert_allclose(out["random"], [1.0, 1.0])
    assert np.isnan(out["s"][0])
    assert out["s"][1] == pytest.approx(0.5, rel=1e-12)
    with pytest.raises(ValueError, match="at least two distinct positive"):
        samples_for_equal_error({"random": [1.0]}, [100])


@pytest.mark.parametrize("shape", [(1, 1), (1, 7), (7, 1)])
def test_a_grid_of_one_row_or_column_has_a_pitch(shape):
    # 1 / sqrt(1/4) = 2 px whatever the grid, as long as it has a cell
    assert sparsest_pitch(shape, [0.25, 1.0]) == pytest.approx(2.0)


@pytest.mark.parametrize("shape", [(0, 5), (5, 0), (0, 0), (-1, 4)])
def test_a_grid_without_cells_has_no_pitch(shape):
    with pytest.raises(ValueError, match=r"shape must be \(rows, cols\) >= 1"):
        sparsest_pitch(shape, [0.25])
