"""What the reconstruction learns of its points in one pass (``scan_points``), by hand:
finite, sorted (non-decreasing rows, then columns), a repeated neighbour, integer, extent."""

from __future__ import annotations

import numpy as np

from simlunar.reconstruction._raster import scan_points


def test_sorted_points_with_a_repeat_are_sorted_and_flagged_as_duplicates():
    """(0, 1), (2, 3), (2, 3), (4, 0): rows 0 <= 2 <= 2 <= 4 and, within row 2, columns 3 <=
    3: non-decreasing, so sorted (the sort is skipped), with two equal neighbours; all
    integers; extent max(4 - 0, 3 - 0) = 4."""
    pts = np.array([[0.0, 1.0], [2.0, 3.0], [2.0, 3.0], [4.0, 0.0]])
    assert tuple(scan_points(pts)) == (True, True, True, True, 4.0)


def test_a_step_back_within_a_row_is_unsorted_and_fractions_are_not_integer():
    """(1, 2.5) after (1, 3): the column decreases within row 1 (unsorted, no repeat seen);
    2.5 is no integer; extent max(1 - 0, 3 - 0) = 3."""
    pts = np.array([[0.0, 0.0], [1.0, 3.0], [1.0, 2.5]])
    assert tuple(scan_points(pts)) == (True, False, False, False, 3.0)


def test_a_nan_point_is_not_finite_and_left_out_of_the_extent():
    pts = np.array([[0.0, 0.0], [np.nan, 5.0], [2.0, 1.0]])
    finite, _, _, _, extent = scan_points(pts)
    assert finite is False and extent == 2.0
