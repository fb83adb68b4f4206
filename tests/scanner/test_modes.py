"""Scan modes on exact synthetic planes (NumPy capture, no Mitsuba)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import modes, rigs
from tests.scanner._synthetic import PlaneCapture


@pytest.fixture
def rig():
    return rigs.moonyard_rig(proj_size=(64, 48), cam_size=(128, 96))


@pytest.mark.parametrize("normal", [(0, 0, 1.0), (0.3, -0.2, 1.0)])
def test_gray_code_scan_of_plane_matches_truth(rig, normal):
    cap = PlaneCapture(rig, normal, 0.0, noise=0.002)
    g = modes.gray_code_scan(cap, rig, black_threshold=0.2, white_threshold=0.05)
    assert g.renders == 6 + 6 + 2 == cap.renders  # bits + 2 with inverses by linearity
    truth = cap.true_depth(rig.guide)
    ok = np.isfinite(g.depth)
    assert ok.mean() > 0.9
    # gray code quantises to whole projector columns: one column spans a depth interval of
    # about dz = z^2 / (f_p * b) along a ray (triangulation depth resolution); the decoded
    # point sits within half a column of the truth, so |error| <= dz / 2 plus the change of
    # depth across the guide pixel (half a pixel on the slope), here bounded by dz as well.
    dz = truth[ok] ** 2 / (rig.projector.intrinsics.fx * rig.baseline)
    err = np.abs(g.depth[ok] - truth[ok])
    assert np.all(err <= dz)
    assert np.median(err / dz) < 0.5
    ref = modes.gray_code_scan(
        cap, rig, black_threshold=0.2, white_threshold=0.05, inverses="render"
    )
    assert ref.renders == 2 * 12 + 2
    np.testing.assert_array_equal(ref.decode.col, g.decode.col)


def test_dot_scan_exact_and_multiplexed_agree(rig, rng):
    cap = PlaneCapture(rig, (0.1, 0.2, 1.0), 0.0, ss=4, noise=0.001)
    truth = cap.true_depth(rig.guide)
    rc = np.stack([rng.integers(2, 46, 250), rng.integers(2, 62, 250)], axis=-1)
    rc = np.unique(rc, axis=0)
    uv = np.c_[rc[:, 1] + 0.5, rc[:, 0] + 0.5]
    rng_z = (np.nanmin(truth) * 0.9, np.nanmax(truth) * 1.1)
    multi = modes.dot_scan(cap, rig, uv, depth_range=rng_z, abs_threshold=0.05)
    exact = modes.dot_scan(cap, rig, uv, depth_range=rng_z, exact=True, abs_threshold=0.05)
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


def test_empty_dot_set_and_bad_budget_are_rejected(rig):
    cap = PlaneCapture(rig, (0, 0, 1.0), 0.0)
    with pytest.raises(ValueError, match="dot set is empty"):
        modes.dot_scan(cap, rig, np.empty((0, 2)), depth_range=(1.0, 2.0))
    with pytest.raises(ValueError, match="budget"):
        modes._budget_k(0.0, 100)
    with pytest.raises(ValueError, match=r"valid: \['ambiguity_enhancement', 'data_reduction'"):
        modes.scan("laser", cap, rig)


def test_gray_code_mode_fills_holes(rig):
    cap = PlaneCapture(rig, (0, 0, 1.0), 0.0)
    res = modes.scan("gray_code", cap, rig, gray_opts={"black_threshold": 0.2})
    assert np.isfinite(res.depth).all() and np.isnan(res.measured).any()
