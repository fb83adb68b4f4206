"""The dot scan (exact and multiplexed) and ambiguity enhancement's fusion of dots on exact
synthetic planes (NumPy capture, no Mitsuba)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from simlunar.scanner import rigs
from simlunar.scanner.dot_scan import DotOptions, dot_scan
from simlunar.scanner.gray_code import GrayCodeOptions
from simlunar.sensors import StructuredLight, StructuredLightOptions
from simlunar.sensors.structured_light import MODES
from tests.scanner._synthetic import PlaneCapture


@pytest.fixture
def rig():
    return rigs.moonyard_rig(proj_size=(64, 48), cam_size=(128, 96))


def test_dot_scan_exact_and_multiplexed_agree(rig, rng):
    cap = PlaneCapture(rig, (0.1, 0.2, 1.0), 0.0, ss=4, noise=0.001)
    truth = cap.true_depth(rig.guide)
    rc = np.stack([rng.integers(2, 46, 250), rng.integers(2, 62, 250)], axis=-1)
    rc = np.unique(rc, axis=0)
    uv = np.c_[rc[:, 1] + 0.5, rc[:, 0] + 0.5]
    rng_z = (np.nanmin(truth) * 0.9, np.nanmax(truth) * 1.1)
    multi = dot_scan(cap, rig, uv, depth_range=rng_z, options=DotOptions(abs_threshold=0.05))
    exact = dot_scan(
        cap, rig, uv, depth_range=rng_z, options=DotOptions(exact=True, abs_threshold=0.05)
    )
    assert exact.renders == len(uv) + 1
    assert multi.renders * 5 < exact.renders
    both = multi.found & exact.found
    assert both.mean() > 0.95
    d_m = multi.depth[rc[both, 0], rc[both, 1]]
    d_e = exact.depth[rc[both, 0], rc[both, 1]]
    # frames carry independent noise, so the two modes differ a little; the benchmark's
    # criterion is a median below 1/10 of a guide pixel's footprint
    assert np.median(np.abs(d_m - d_e)) < rigs.footprint(rig, float(np.median(d_e))) / 10
    # a dot at a projector pixel centre measures the guide ray's depth there, up to the
    # centroid error in the camera; 0.1 camera px of disparity is dz = 0.1 z^2 / (f_c b)
    z = truth[rc[both, 0], rc[both, 1]]
    dz_cam = 0.1 * z**2 / (rig.camera.intrinsics.fx * rig.baseline)
    assert np.median(np.abs(d_e - z) / dz_cam) < 1.0


def test_empty_dot_set_and_bad_options_are_rejected(rig):
    cap = PlaneCapture(rig, (0, 0, 1.0), 0.0)
    with pytest.raises(ValueError, match="dot set is empty"):
        dot_scan(cap, rig, np.empty((0, 2)), depth_range=(1.0, 2.0))
    with pytest.raises(ValueError, match=re.escape(f"valid: {sorted(MODES)}")):
        StructuredLightOptions(mode="laser")
    with pytest.raises(ValueError, match="inverses must be one of 'linearity', 'render'"):
        GrayCodeOptions(inverses="both")
    with pytest.raises(ValueError, match="batch must be >= 1"):
        DotOptions(batch=0)
    with pytest.raises(ValueError, match=r"min_proj_spacing must be >= 0, got -1.0"):
        DotOptions(min_proj_spacing=-1.0)


def test_ambiguity_enhancement_shares_the_gray_code_and_fuses_dots(rig):
    cap = PlaneCapture(rig, (0.1, 0.0, 1.0), 0.0, noise=0.0)
    opts = StructuredLightOptions(
        "ambiguity_enhancement", codings={"gray_code": GrayCodeOptions(black_threshold=0.2)}
    )
    sensor = StructuredLight(cap, rig, depth_range=(1.0, 3.0), options=opts)
    rc = np.array([[10, 10], [20, 30], [40, 50]])
    acq = sensor.acquire(rc)
    res = acq.detail
    hit = np.isfinite(res.dots.depth)
    assert hit.any()
    np.testing.assert_array_equal(res.measured[hit], res.dots.depth[hit])
    assert acq.frames == res.dots.renders  # the shared gray code is not counted again
    assert sensor.acquire(rc).detail.coded is res.coded  # scanned once
    with pytest.raises(ValueError, match="rc is required"):
        sensor.acquire(None)
