"""The platform's trajectory."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar.trajectory import Trajectory


def test_hover_and_descent_by_hand():
    h = Trajectory.hover([1.0, 2.0, 50.0])
    assert h.at([0.0, 10.0]) == pytest.approx(np.array([[1.0, 2.0, 50.0]] * 2))
    d = Trajectory.descent([0.0, 0.0, 50.0], 2.0, horizontal_m_s=(0.5, 0.0))
    assert d.at(3.0) == pytest.approx([1.5, 0.0, 44.0])
    assert d.at(np.zeros((2, 4))).shape == (2, 4, 3)


def test_bad_trajectory():
    with pytest.raises(ValueError, match="position_m must be 3 finite numbers"):
        Trajectory((0.0, np.nan, 1.0))
