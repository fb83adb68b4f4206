"""Stage helpers: per-stage seeds, hole filling, luminance, the sensor stage."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.config.render import SensorCfg
from simlunar.pipeline.unit import STAGES, fill_invalid, luminance, sensor_image, stage_seeds


def test_stage_seeds_are_independent_and_depend_only_on_the_seed():
    a, b = stage_seeds(4), stage_seeds(4)
    states = {k: tuple(v.generate_state(4)) for k, v in a.items()}
    assert states == {k: tuple(v.generate_state(4)) for k, v in b.items()}
    assert len(set(states.values())) == len(STAGES)  # no two stages share a stream
    assert tuple(stage_seeds(5)["terrain"].generate_state(4)) != states["terrain"]
    # the terrain stream is the first child of SeedSequence(seed): stable across versions
    assert states["terrain"] == tuple(np.random.SeedSequence(4).spawn(1)[0].generate_state(4))


def test_fill_invalid_takes_the_nearest_valid_pixel():
    d = np.array([[1.0, np.nan, 3.0], [4.0, 5.0, 6.0], [np.nan, 8.0, 9.0]])
    filled, n = fill_invalid(d)
    assert n == 2
    assert filled[2, 0] in (4.0, 8.0)  # both at distance 1
    assert filled[0, 1] in (1.0, 3.0, 5.0)
    np.testing.assert_array_equal(filled[np.isfinite(d)], d[np.isfinite(d)])
    same, n0 = fill_invalid(np.ones((2, 2)))
    assert n0 == 0 and np.all(same == 1)
    with pytest.raises(ValueError, match="no pixel of the view sees the terrain"):
        fill_invalid(np.full((2, 2), np.nan))


def test_luminance_rec709():
    rgb = np.zeros((1, 3, 3), np.float32)
    rgb[0, 0, 0] = rgb[0, 1, 1] = rgb[0, 2, 2] = 1.0
    np.testing.assert_allclose(luminance(rgb)[0], [0.2126, 0.7152, 0.0722], rtol=1e-6)


def test_sensor_stage(rng):
    rad = rng.random((32, 32)).astype(np.float32) * 0.1
    clean = sensor_image(rad, None, rng=0)
    # the auto-exposure rule without a sensor: the 99.5th percentile at 0.8, clipped to 1
    assert clean.dtype == np.float32
    assert np.percentile(clean, 99.5) == pytest.approx(0.8, rel=1e-6)
    np.testing.assert_allclose(clean, np.clip(rad * (0.8 / np.percentile(rad, 99.5)), 0, 1))
    noisy = sensor_image(rad, SensorCfg(bits=8), rng=1)
    assert noisy.dtype == np.float32 and 0 <= noisy.min() and noisy.max() <= 1
    # 8 bits: values on the 1/255 lattice
    np.testing.assert_allclose(noisy * 255, np.round(noisy * 255), atol=1e-4)
    np.testing.assert_array_equal(noisy, sensor_image(rad, SensorCfg(bits=8), rng=1))
