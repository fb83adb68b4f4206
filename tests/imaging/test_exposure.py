"""The one auto-exposure rule: the 99.5th percentile of the reference at 80 % of the range."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.imaging.exposure import auto_exposure_e, auto_gain


def test_auto_gain_hand_computed():
    # 0, 1, ..., 199: the linear-interpolation 99.5th percentile sits at rank 0.995 * 199
    ref = np.arange(200, dtype=np.float64)
    p = 0.995 * 199  # rank of the 99.5th percentile (linear interpolation): 198.005
    assert auto_gain(ref) == pytest.approx(0.8 / p)
    assert auto_exposure_e(ref, 20000.0) == pytest.approx(0.8 * 20000.0 / p)
    # NaN counts as 0; a black reference has nothing to expose for
    assert auto_gain(np.zeros((4, 4))) == 1.0
    assert auto_exposure_e(np.full((4, 4), np.nan), 1000.0) == 1000.0


def test_sampling_sensor_fills_80_percent_of_the_well():
    """sensor: {exposure_e: null} in a sampling study: the 99.5th pct reads 0.8 of the ADC."""
    from simlunar.config.render import SensorCfg
    from simlunar.pipeline.unit import sensor_image

    rad = np.random.default_rng(3).random((64, 64)).astype(np.float32) * 7.0
    # a huge well makes shot noise negligible; no read noise, 16 bits
    img = sensor_image(rad, SensorCfg(full_well_e=1e12, read_noise_e=0, bits=16), rng=0)
    assert np.percentile(img, 99.5) == pytest.approx(0.8, abs=2e-5)
    fixed = sensor_image(
        rad, SensorCfg(full_well_e=1e12, read_noise_e=0, bits=16, exposure_e=1e10), rng=0
    )
    assert fixed.max() == pytest.approx(7.0 * 1e10 / 1e12, rel=1e-3)  # a fixed exposure is kept


@pytest.mark.render
def test_scanner_capture_uses_the_rule_on_its_white_frame():
    """RenderCapture exposes the sensor by the same rule, on its white calibration frame."""
    from simlunar.imaging.sensor import SensorModel
    from simlunar.render.capture import CaptureOptions, RenderCapture
    from simlunar.scanner import rigs
    from simlunar.terrain.types import Terrain

    n = 60
    x = np.linspace(-1, 1, n)
    heights = 0.05 * np.sin(3 * x)[None, :] * np.ones((n, 1))
    albedo = np.where(np.add.outer(np.arange(n), np.arange(n)) % 7 < 3, 0.2, 0.6)
    terr = Terrain(heights, albedo.astype(np.float32), 2.0 / n, (-1.0, 1.0))
    rig = rigs.moonyard_rig(proj_size=(32, 24), cam_size=(40, 30))
    sensor = SensorModel(exposure=1.0, full_well_e=5000.0, read_noise_e=0.0, bits=12)
    cap = RenderCapture(terr, rig, CaptureOptions(max_depth=2, spp=2, seed=1), sensor=sensor)
    white = cap._lens(cap.scene.render_patterns(np.ones((1, 24, 32), np.float32)))[0]
    assert cap.gain == pytest.approx(auto_gain(white), rel=1e-6)
    assert cap.sensor.exposure == pytest.approx(auto_exposure_e(white, 5000.0), rel=1e-6)
