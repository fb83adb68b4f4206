"""Landing hazards: slopes and rocks on hand-made surfaces, detection precision and recall."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics.hazard import HazardOptions, detection_scores, hazard_map


def _grid(z: np.ndarray, spacing: float = 0.5) -> np.ndarray:
    r, c = np.mgrid[0 : z.shape[0], 0 : z.shape[1]] * spacing
    return np.stack([c, -r, z], axis=-1)


def test_a_flat_plane_has_no_hazard():
    assert not hazard_map(_grid(np.zeros((30, 30)))).any()


@pytest.mark.parametrize("angle, steep", [(10.0, False), (20.0, True)])
def test_a_tilted_plane_is_steep_above_the_limit(angle, steep):
    c = np.mgrid[0:30, 0:30][1] * 0.5
    flags = hazard_map(_grid(np.tan(np.radians(angle)) * c), HazardOptions(slope_deg=15.0))
    inner = flags[2:-2, 2:-2]  # central differences need baseline_px cells each side
    assert inner.all() if steep else not inner.any()


def test_a_rock_stands_above_the_local_median():
    z = np.zeros((40, 40))
    z[18:21, 18:21] = 0.5  # a 1.5 m wide, 0.5 m high block
    flags = hazard_map(_grid(z), HazardOptions(relief_m=0.3, slope_deg=89.0))
    assert flags[18:21, 18:21].all()
    assert flags.sum() == 9


def test_unknown_points_are_never_hazards():
    z = np.zeros((20, 20))
    z[5, 5] = np.nan
    assert not hazard_map(_grid(z))[5, 5]


def test_detection_scores_by_hand():
    truth = np.zeros((4, 4), bool)
    truth[0, :2] = True
    found = np.zeros((4, 4), bool)
    found[0, 0] = found[3, 3] = True
    assert detection_scores(found, truth) == {"hazard_precision": 0.5, "hazard_recall": 0.5}
    none = np.zeros((4, 4), bool)
    assert detection_scores(none, none) == {"hazard_precision": 1.0, "hazard_recall": 1.0}


def test_hazard_options_refuse_bad_values():
    with pytest.raises(ValueError, match="window_px must be odd, got 4"):
        HazardOptions(window_px=4)
    with pytest.raises(ValueError, match=r"slope_deg must be > 0, got 0\.0"):
        HazardOptions(slope_deg=0.0)
    with pytest.raises(ValueError, match="baseline_px must be >= 1, got 0"):
        HazardOptions(baseline_px=0)


def test_detection_scores_count_only_cells_inside_the_mask():

    truth = np.array([[1, 1, 0, 0]], bool)
    found = np.array([[1, 0, 1, 0]], bool)
    # whole grid: 1 true positive of 2 flagged and of 2 true hazards
    assert detection_scores(found, truth) == {"hazard_precision": 0.5, "hazard_recall": 0.5}
    # the mask drops the false alarm (col 2) and the missed hazard (col 1)
    mask = np.array([[1, 0, 0, 1]], bool)
    assert detection_scores(found, truth, mask) == {"hazard_precision": 1.0, "hazard_recall": 1.0}
    # a mask keeping only the false alarm: precision 0, nothing to miss
    mask = np.array([[0, 0, 1, 0]], bool)
    assert detection_scores(found, truth, mask) == {"hazard_precision": 0.0, "hazard_recall": 1.0}


def test_the_default_relief_limit_is_0_3_m():
    """HazardOptions() flags what stands more than 0.3 m above the local median: a 0.5 m
    block is a rock, a 0.2 m one is not (flat ground, no slope limit in the way)."""
    for height, rock in ((0.5, True), (0.2, False)):
        z = np.zeros((40, 40))
        z[18:21, 18:21] = height
        flags = hazard_map(_grid(z), HazardOptions(slope_deg=89.0))
        assert flags[18:21, 18:21].all() == rock
