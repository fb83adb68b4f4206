"""The point emitter's irradiance: inverse square, incidence and the cos^n beam, by hand."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import beam_intensity, beam_profile, point_irradiance


def test_nadir_irradiance_of_a_flash_by_hand():
    # a 2 kJ flash over a 10 ms exposure, cos^4 beam: I0 = Q (n + 1) / (2 pi t) W/sr; 50 m
    # above the ground, 5 m east of the camera, looking down: below it E = I0 / 50^2
    q, t, n = 2000.0, 0.01, 4.0
    i0 = beam_intensity(q, t, n)
    assert i0 == pytest.approx(2000.0 * 5.0 / (2 * np.pi * 0.01), rel=1e-15)  # 159154.9 W/sr
    e = point_irradiance([5.0, 0.0, 0.0], [0, 0, 1.0], position=[5.0, 0, 50.0],
                         axis=[0, 0, -1.0], intensity=i0, beam_exponent=n)  # fmt: skip
    assert float(e) == pytest.approx(159154.94309189535 / 2500.0, rel=1e-6)  # 63.66 W/m^2
    # against the sun at 30 deg (1361 cos 60 deg = 680.5 W/m^2 on the same ground): 9.4 %
    assert float(e) / (1361 * np.cos(np.radians(60))) == pytest.approx(0.09355, rel=1e-3)


def test_off_axis_point_carries_beam_incidence_and_distance():
    # light at (0, 0, 3) looking down; ground point (4, 0, 0): d = 5, cos(theta) = cos(i) = 3/5
    e = point_irradiance([[4.0, 0, 0]], [[0, 0, 2.0]], position=[0, 0, 3.0], axis=[0, 0, -7.0],
                         intensity=10.0, beam_exponent=2.0)  # fmt: skip
    assert e[0] == pytest.approx(10.0 * 0.6**2 * 0.6 / 25.0, rel=1e-12)
    # a wall facing the light along x: cos(i) = 4/5 (normal (-1, 0, 0)), beam still 3/5
    e = point_irradiance([4.0, 0, 0], [-1.0, 0, 0], position=[0, 0, 3.0], axis=[0, 0, -1.0],
                         intensity=10.0, beam_exponent=2.0)  # fmt: skip
    assert float(e) == pytest.approx(10.0 * 0.6**2 * 0.8 / 25.0, rel=1e-12)
    # facing away: nothing; beyond the cutoff (53.1 deg > 45): nothing
    assert float(point_irradiance([4.0, 0, 0], [1.0, 0, 0], position=[0, 0, 3.0],
                                  axis=[0, 0, -1.0])) == 0.0  # fmt: skip
    assert float(point_irradiance([4.0, 0, 0], [0, 0, 1.0], position=[0, 0, 3.0],
                                  axis=[0, 0, -1.0], cutoff=np.radians(45))) == 0.0  # fmt: skip


def test_beam_power_integrates_to_the_energy():
    # sum of I(theta) dOmega over the hemisphere = 2 pi I0 / (n + 1) = Q / t
    n = 3.0
    i0 = beam_intensity(1.0, 1.0, n)
    th = np.linspace(0, np.pi / 2, 200001)
    p = np.trapezoid(i0 * beam_profile(np.cos(th), n) * 2 * np.pi * np.sin(th), th)
    assert p == pytest.approx(1.0, rel=1e-8)


def test_bad_inputs():
    with pytest.raises(ValueError, match="exposure > 0"):
        beam_intensity(1.0, 0.0, 1.0)
    with pytest.raises(ValueError, match="coincides"):
        point_irradiance([0, 0, 1.0], [0, 0, 1.0], position=[0, 0, 1.0], axis=[0, 0, -1.0])
