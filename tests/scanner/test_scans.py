"""Structured-light scans and the scanner sensor's modes on exact synthetic planes (NumPy
capture, no Mitsuba)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import rigs
from simlunar.scanner import scans as modes
from simlunar.scanner.scans import DotOptions, GrayCodeOptions
from simlunar.sensors import StructuredLight, StructuredLightOptions
from tests.scanner._synthetic import PlaneCapture


@pytest.fixture
def rig():
    return rigs.moonyard_rig(proj_size=(64, 48), cam_size=(128, 96))


@pytest.mark.parametrize("normal", [(0, 0, 1.0), (0.3, -0.2, 1.0)])
def test_gray_code_scan_of_plane_matches_truth(rig, normal):
    cap = PlaneCapture(rig, normal, 0.0, noise=0.002)
    g = modes.gray_code_scan(cap, rig, GrayCodeOptions(black_threshold=0.2, white_threshold=0.05))
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
        cap, rig, GrayCodeOptions(black_threshold=0.2, white_threshold=0.05, inverses="render")
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
    multi = modes.dot_scan(cap, rig, uv, depth_range=rng_z, options=DotOptions(abs_threshold=0.05))
    exact = modes.dot_scan(
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
        modes.dot_scan(cap, rig, np.empty((0, 2)), depth_range=(1.0, 2.0))
    with pytest.raises(ValueError, match=r"valid: \['ambiguity_enhancement', 'data_reduction'"):
        StructuredLightOptions(mode="laser")
    with pytest.raises(ValueError, match="inverses must be one of 'linearity', 'render'"):
        GrayCodeOptions(inverses="both")
    with pytest.raises(ValueError, match="batch must be >= 1"):
        DotOptions(batch=0)
    with pytest.raises(ValueError, match=r"min_proj_spacing must be >= 0, got -1.0"):
        DotOptions(min_proj_spacing=-1.0)


def test_gray_code_mode_measures_the_decoded_pixels(rig):
    cap = PlaneCapture(rig, (0, 0, 1.0), 0.0)
    gray = StructuredLightOptions(
        "gray_code", codings={"gray_code": GrayCodeOptions(black_threshold=0.2)}
    )
    sensor = StructuredLight(cap, rig, depth_range=(1.0, 3.0), options=gray)
    assert not sensor.needs_plan
    acq = sensor.acquire(None)
    res = acq.detail
    assert np.isnan(res.measured).any() and acq.frames == res.renders == 14
    # the acquisition holds exactly the finite cells of the measured map, row-major
    np.testing.assert_array_equal(acq.measured_map(), res.measured)
    assert len(acq.values) == np.isfinite(res.measured).sum()


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


def _decode_of(contrast: np.ndarray, proj_shape=(2, 4)):
    """A gray-code decode of a camera that sees the projector pixel for pixel (camera shape =
    projector shape), each pixel lit with ``contrast`` (white - black), black 0.1."""
    from simlunar.scanner import gray_code as gc

    H, W = proj_shape
    pats = gc.encode(W, H).astype(float)  # (pattern, inverse) pairs
    black = np.full((H, W), 0.1)
    frames = black + pats * contrast
    return gc.decode(frames, black + contrast, black, proj_shape=(H, W),
                     black_threshold=0.01, white_threshold=0.001)  # fmt: skip


def test_decode_keeps_the_contrast():
    c = np.array([[0.5, 0.2, 0.9, 0.05], [0.3, 0.7, 0.6, 0.4]])
    dec = _decode_of(c)
    assert dec.contrast.dtype == np.float32
    np.testing.assert_allclose(dec.contrast, c, rtol=1e-6)
    assert np.all(dec.col == np.arange(4)) and np.all(dec.row.T == np.arange(2))


def test_low_contrast_planner_picks_the_least_lit_projector_pixels():
    c = np.array([[0.5, 0.2, 0.9, 0.05], [0.3, 0.7, 0.6, 0.004]])
    dec = _decode_of(c)  # (1, 3) is below black_threshold 0.01: unlit, ranked last
    assert dec.col[1, 3] == -1 and [a[1, 3] for a in dec.decoded_index()] == [3, 1]
    g = modes.GrayScan(decode=dec, cloud=None, depth=np.zeros(dec.proj_shape), renders=0, frames={})
    rc = modes.low_contrast_pixels(g, 3, rng=0)
    assert rc.tolist() == [[0, 3], [0, 1], [1, 0]]  # contrasts 0.05, 0.2, 0.3
    everything = modes.low_contrast_pixels(g, 8, rng=0)
    assert everything[-1].tolist() == [1, 3]
    with pytest.raises(ValueError, match=r"k must be in 1\.\.8"):
        modes.low_contrast_pixels(g, 9, rng=0)


def test_low_contrast_planner_takes_the_dimmest_camera_pixel_of_a_projector_pixel():
    # two camera pixels decode to each projector column: the projector pixel's rank is the
    # lower contrast of the two (a wrongly decoded dim pixel corrupts the depth there)
    from simlunar.scanner import gray_code as gc

    H, W = 2, 4
    pats = gc.encode(W, H).astype(float)
    cam = np.repeat(pats, 2, axis=2)  # camera (2, 8): pixels 2j, 2j+1 see column j
    c = np.array([[0.9, 0.8, 0.15, 0.9, 0.5, 0.6, 0.3, 0.35], [0.95] * 8])
    dec = gc.decode(cam * c, c, np.zeros_like(c), proj_shape=(H, W),
                    black_threshold=0.01, white_threshold=0.001)  # fmt: skip
    g = modes.GrayScan(decode=dec, cloud=None, depth=np.zeros((H, W)), renders=0, frames={})
    # row 0 by the lower contrast of its two camera pixels: 0.15, 0.3, 0.5, 0.8
    assert modes.low_contrast_pixels(g, 4, rng=0).tolist() == [[0, 1], [0, 3], [0, 2], [0, 0]]
