"""Dot patterns, sub-pixel centroids, ghost rejection and epipolar segments (the multiplexed
scheduling of dots is tested in test_scheduling.py)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import dots, rigs, scheduling


def gaussian_spots(shape, centres, sigma, amplitude=1.0):
    """Pixel-integrated isotropic Gaussians (erf differences), so the true centroid is exact."""
    from scipy.special import erf

    rows, cols = shape
    img = np.zeros(shape)
    for u, v in np.atleast_2d(centres):
        s = sigma * np.sqrt(2)
        cu = np.arange(cols + 1)
        cv = np.arange(rows + 1)
        gu = np.diff(0.5 * erf((cu - u) / s))
        gv = np.diff(0.5 * erf((cv - v) / s))
        img += amplitude * np.outer(gv, gu)
    return img


def test_dot_pattern_single_pixel_and_disk():
    p = dots.dot_pattern((6, 8), [[2.7, 4.1]])
    assert p.sum() == 1 and p[4, 2] == 1
    d = dots.dot_pattern((20, 20), [[10.0, 10.0]], radius=1.5)
    # pixel centres within 1.5 px of (10, 10): the 4 centres at distance 0.71 and 8 at 1.58? no:
    # offsets (+-0.5, +-0.5) -> 0.71 (4 pixels), (+-1.5, +-0.5) -> 1.58 > 1.5, so exactly 4
    assert d.sum() == 4
    d2 = dots.dot_pattern((20, 20), [[10.5, 10.5]], radius=1.0)
    assert d2.sum() == 5  # the centre pixel and its 4 edge neighbours at distance 1
    with pytest.raises(ValueError, match="empty"):
        dots.dot_pattern((6, 8), np.empty((0, 2)))
    with pytest.raises(ValueError, match="inside"):
        dots.dot_pattern((6, 8), [[8.0, 1.0]])


@pytest.mark.parametrize("centre", [(20.37, 15.81), (11.5, 9.02), (30.93, 20.49)])
def test_subpixel_centroid_of_gaussian_and_disk(centre):
    img = gaussian_spots((40, 48), centre, sigma=1.3)
    det = dots.detect_dots(img, background=0.0)
    assert len(det) == 1
    assert np.hypot(*(det.uv[0] - centre)) < 0.05
    # a uniform disk of radius 2.5 px, area-sampled on a 16x16 sub-grid per pixel
    ss = 16
    v, u = (np.mgrid[0 : 40 * ss, 0 : 48 * ss] + 0.5) / ss
    disk = (np.hypot(u - centre[0], v - centre[1]) <= 2.5).reshape(40, ss, 48, ss).mean(axis=(1, 3))
    det = dots.detect_dots(disk + 0.1, background=0.1)
    assert np.hypot(*(det.uv[0] - centre)) < 0.05


def test_detect_dots_with_no_signal_is_empty():
    assert len(dots.detect_dots(np.full((10, 10), 0.3))) == 0


@pytest.fixture
def rig():
    return rigs.moonyard_rig(proj_size=(128, 96), cam_size=(160, 120))


def test_ghosts_are_rejected(rig):
    proj_uv = np.array([[64.5, 48.5]])
    X = rig.projector.pose.device_to_world(rig.projector.directions_device(proj_uv) * 1.6)
    true_uv, _ = rig.camera.project(X)
    seg = dots.epipolar_segments(rig, proj_uv, (1.0, 3.0))
    off_line = true_uv[0] + np.array([0.0, 25.0])  # interreflection 25 px off the epipolar line
    on_line = seg[0, 0]  # a dimmer ghost lying on the segment (at its near end)
    assert np.hypot(*(on_line - true_uv[0])) > 8
    img = (
        gaussian_spots((120, 160), true_uv, 1.0)
        + gaussian_spots((120, 160), off_line, 1.0, 0.5)
        + gaussian_spots((120, 160), on_line, 1.0, 0.4)
    )
    det = dots.detect_dots(img, background=0.0)
    assert len(det) == 3
    m = dots.match_dots(det, seg, tol=2.0)
    assert m.dot.tolist() == [0] and m.n_ghosts == 2
    assert np.hypot(*(m.cam_uv[0] - true_uv[0])) < 0.05


def _dense_segment_distance(a, b, k=4001):
    """Brute force: distance between k samples of ``a`` and the exact segment ``b``."""
    t = np.linspace(0.0, 1.0, k)
    pts = a[0] + t[:, None] * (a[1] - a[0])
    return dots.point_segment_distance(pts, b[None]).min()


def test_segment_distance_hand_cases_and_brute_force(rng):
    h = np.array([[0.0, 0.0], [10.0, 0.0]])
    cases = [
        (np.array([[2.0, 3.0], [8.0, 3.0]]), 3.0),  # parallel, overlapping: the offset
        (np.array([[13.0, 4.0], [20.0, 4.0]]), 5.0),  # parallel, disjoint: end to end (3-4-5)
        (np.array([[5.0, -1.0], [5.0, 1.0]]), 0.0),  # crossing
        (np.array([[12.0, 0.0], [15.0, 0.0]]), 2.0),  # collinear gap
        (np.array([[5.0, 2.0], [5.0, 7.0]]), 2.0),  # T: endpoint over the interior
        (np.array([[10.0, 0.0], [11.0, 5.0]]), 0.0),  # touching at an end
    ]
    for seg, want in cases:
        assert dots.segment_distance(h, seg) == pytest.approx(want, abs=1e-12)
        assert dots.segment_distance(seg, h) == pytest.approx(want, abs=1e-12)
    a = rng.uniform(0, 10, size=(200, 2, 2))
    b = rng.uniform(0, 10, size=(200, 2, 2))
    d = dots.segment_distance(a, b)
    brute = np.array(
        [min(_dense_segment_distance(x, y), _dense_segment_distance(y, x)) for x, y in zip(a, b)]
    )
    # sampling only overestimates, by at most half a sample step of the longer segment
    assert np.all(d <= brute + 1e-12)
    assert np.all(brute - d <= 10 * np.sqrt(2) / 4000 / 2 + 1e-9)


def test_camera_that_does_not_see_the_projection_is_rejected():
    r = rigs.make_rig(
        target=(0, 0, 0),
        distance=1.0,
        elevation=np.pi / 2,
        baseline=0.3,
        proj_size=(32, 24),
        proj_fov_x=0.5,
        camera=rigs.RigCamera(verge=False),
    )
    from simlunar.geometry import Camera, Pose, Rig

    away = Camera(
        r.camera.intrinsics,
        Pose.look_at(r.camera.position, r.camera.position + np.array([0, 0, 1.0])),
    )
    bad = Rig(r.projector, away)
    with pytest.raises(ValueError, match="does not see the projected area"):
        dots.epipolar_segments(bad, [[16.0, 12.0]], (0.5, 1.5))
    with pytest.raises(ValueError, match="empty"):
        scheduling.schedule_dots(r, np.empty((0, 2)), depth_range=(0.5, 1.5))


def test_spots_cut_by_the_image_border_are_dropped():
    img = gaussian_spots((30, 40), [(0.8, 15.0), (20.0, 15.0)], sigma=1.0)
    det = dots.detect_dots(img, background=0.0)
    assert len(det) == 1 and np.hypot(*(det.uv[0] - (20.0, 15.0))) < 0.05
    assert len(dots.detect_dots(img, background=0.0, reject_border=False)) == 2


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("grow", [0, 1, 2, 3])
def test_compiled_detection_equals_the_scipy_reference(seed, grow):
    from reference_scanner import detect_dots_reference

    rng = np.random.default_rng(seed)
    shape = (70, 90)
    centres = np.c_[rng.uniform(-2, 92, 25), rng.uniform(-2, 72, 25)]  # some cut by the border
    img = gaussian_spots(shape, centres, sigma=0.9, amplitude=rng.uniform(0.2, 1.0))
    img += 0.01 * rng.random(shape)
    bg = 0.005 * rng.random(shape)
    for kw in ({}, {"reject_border": False}, {"rel_threshold": 0.05, "abs_threshold": 0.02}):
        ours = dots.detect_dots(img.astype(np.float32), background=bg, grow=grow, **kw)
        ref = detect_dots_reference(img.astype(np.float32), background=bg, grow=grow, **kw)
        assert len(ref) > 5
        assert len(ours) == len(ref)
        # a pixel equidistant from two blobs' pixels (blobs a few px apart) may be grown into
        # either: the two implementations break such ties differently (seen: 0.03 px)
        np.testing.assert_allclose(ours.uv, ref.uv, atol=0.05)
        np.testing.assert_allclose(ours.flux, ref.flux, rtol=0.05)
        alone = np.array([np.sort(np.hypot(*(ref.uv - p).T))[1] > 4 * grow + 4 for p in ref.uv])
        np.testing.assert_allclose(ours.uv[alone], ref.uv[alone], atol=1e-9)
        np.testing.assert_allclose(ours.peak, ref.peak, rtol=1e-12)
