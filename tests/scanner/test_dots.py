"""Dot patterns, sub-pixel centroids, ghost rejection and multiplexed scheduling."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import dots, rigs, scheduling
from simlunar.scanner import triangulate as tri


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


def test_schedule_respects_spacing_and_covers_every_dot(rig, rng):
    proj_uv = rng.uniform([0, 0], [128, 96], size=(600, 2))
    frames = scheduling.schedule_dots(
        rig, proj_uv, depth_range=(1.4, 1.8), min_proj_spacing=6.0, min_cam_spacing=5.0
    )
    allidx = np.sort(np.concatenate(frames))
    np.testing.assert_array_equal(allidx, np.arange(600))
    seg = dots.epipolar_segments(rig, proj_uv, (1.4, 1.8))
    for f in frames:
        if len(f) < 2:
            continue
        p = proj_uv[f]
        dp = np.linalg.norm(p[:, None] - p[None], axis=-1)
        assert dp[np.triu_indices(len(f), 1)].min() >= 6.0
        # segment-segment distance via dense sampling of one side
        s = seg[f]
        t = np.linspace(0, 1, 50)
        samples = s[:, None, 0] + t[None, :, None] * (s[:, None, 1] - s[:, None, 0])
        for i in range(len(f)):
            others = np.delete(np.arange(len(f)), i)
            d = dots.point_segment_distance(samples[i], s[others])
            assert d.min() >= 5.0 - 1e-9
    assert len(frames) < 600 / 5  # multiplexing actually packs dots
    exact = scheduling.schedule_dots(rig, proj_uv, depth_range=(1.4, 1.8), exact=True)
    assert len(exact) == 600 and all(len(f) == 1 for f in exact)


def test_the_scan_path_skips_the_lower_bound(rig, rng, monkeypatch):
    proj_uv = rng.uniform([0, 0], [128, 96], size=(300, 2))
    kw = {"depth_range": (1.4, 1.8), "min_proj_spacing": 6.0, "min_cam_spacing": 5.0}
    full = scheduling.dot_schedule(rig, proj_uv, **kw)
    assert full.lower_bound > 1

    def no_search(*a, **k):
        raise AssertionError("the lower bound was searched")

    monkeypatch.setattr(scheduling, "_largest_clique", no_search)
    fast = scheduling.dot_schedule(rig, proj_uv, bound=False, **kw)
    assert fast.lower_bound == 0 and fast.clique.size == 0
    np.testing.assert_array_equal(fast.colour, full.colour)  # the same frames
    frames = scheduling.schedule_dots(rig, proj_uv, **kw)
    assert [f.tolist() for f in frames] == [f.tolist() for f in full.frames]


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


def _rolled(rig, angle):
    """The rig with its camera rolled about its optical axis (epipolar lines turn by angle)."""
    from simlunar.geometry import Camera, Pose, Rig

    c, s = np.cos(angle), np.sin(angle)
    roll = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    cam = rig.camera
    return Rig(rig.projector, Camera(cam.intrinsics, Pose(cam.pose.rotation @ roll, cam.position)))


def _behind(rig):
    """Camera 0.4 m straight behind the projector: the epipole is inside the image."""
    from simlunar.geometry import Camera, Pose, Rig

    p = rig.projector.pose
    return Rig(
        rig.projector, Camera(rig.camera.intrinsics, Pose(p.rotation, p.position - 0.4 * p.forward))
    )


RIGS = {
    # verged moonyard rig, epipole far off the image side
    "moonyard": lambda: rigs.moonyard_rig(proj_size=(256, 192), cam_size=(512, 384)),
    # camera parallel to the projector: epipole at infinity, rectified rows
    "parallel": lambda: rigs.moonyard_rig(proj_size=(256, 192), cam_size=(512, 384), verge=False),
    # converged with a long baseline and a rolled camera: slanted, fanning epipolar lines
    "rolled": lambda: _rolled(
        rigs.moonyard_rig(proj_size=(256, 192), cam_size=(512, 384), baseline=0.9), 0.6
    ),
    # nadir aerial rig seen from the side at a steep azimuth
    "aerial": lambda: rigs.aerial_rig(proj_size=(256, 192), cam_size=(400, 300), azimuth=2.0),
    # epipole inside the image: lines radiate all around it
    "behind": lambda: _behind(rigs.moonyard_rig(proj_size=(256, 192), cam_size=(512, 384))),
}


def _conflicts(seg, uv, i, j, psp, sep):
    """Exact test for the pairs (i, j): projector distance < psp or segment distance < sep."""
    dp = np.linalg.norm(uv[i] - uv[j], axis=-1)
    return (dp < psp) | (dots.segment_distance(seg[i], seg[j]) < sep)


@pytest.mark.parametrize("name", sorted(RIGS))
def test_schedule_is_conflict_free_under_the_exact_test(name, rng):
    rig = RIGS[name]()
    dist = 1.6 if name != "aerial" else 100.0
    depth_range = (0.8 * dist, 1.25 * dist)
    uv = np.unique(np.floor(rng.uniform([0, 0], [256, 192], size=(2500, 2))) + 0.5, axis=0)
    n = len(uv)
    psp, sep = 8.0, 6.0
    sch = scheduling.dot_schedule(
        rig, uv, depth_range=depth_range, min_proj_spacing=psp, min_cam_spacing=sep
    )
    np.testing.assert_array_equal(np.sort(np.concatenate(sch.frames)), np.arange(n))
    for k, f in enumerate(sch.frames):
        assert np.all(sch.colour[f] == k)
    seg = dots.epipolar_segments(rig, uv, depth_range)
    # every pair of dots that share a frame, against the exact test
    i, j = np.concatenate(
        [np.stack([f[a], f[b]]) for f in sch.frames for a, b in [np.triu_indices(len(f), 1)]],
        axis=1,
    )
    assert not np.any(_conflicts(seg, uv, i, j, psp, sep)), "conflicting dots share a frame"
    # the lower bound is a real clique: every pair in it conflicts
    cl = sch.clique
    a, b = np.triu_indices(len(cl), 1)
    assert len(cl) >= 2 and np.all(_conflicts(seg, uv, cl[a], cl[b], psp, sep))
    assert sch.lower_bound <= len(sch.frames) < n / 4  # dots are actually multiplexed


def test_dots_on_one_epipolar_line_get_the_optimal_schedule(rng):
    # camera parallel to the projector: one projector row maps to one camera row, so the
    # segments are collinear and two dots conflict iff their intervals are < sep apart: an
    # interval graph, whose optimal colouring needs exactly its largest clique
    rig = RIGS["parallel"]()
    cols = np.sort(rng.choice(256, size=120, replace=False)) + 0.5
    uv = np.c_[cols, np.full(120, 77.5)]
    sep = 6.0
    sch = scheduling.dot_schedule(
        rig, uv, depth_range=(1.3, 2.0), min_proj_spacing=1.0, min_cam_spacing=sep
    )
    seg = dots.epipolar_segments(rig, uv, (1.3, 2.0))
    assert np.ptp(seg[..., 1]) < 1e-9  # one camera row
    lo, hi = seg[..., 0].min(axis=1), seg[..., 0].max(axis=1)
    # largest clique: most intervals widened by sep / 2 that contain one left end
    x = lo - sep / 2
    clique = ((lo[None] - sep / 2 <= x[:, None]) & (hi[None] + sep / 2 > x[:, None])).sum(1).max()
    assert clique > 5
    assert sch.lower_bound == clique
    assert len(sch.frames) == clique


def test_schedule_around_an_epipole_inside_the_image():
    # dots on a ring about the projector centre: their camera segments radiate all around the
    # epipole, so the bands close on themselves and the first band meets the last
    rig = _behind(rigs.moonyard_rig(proj_size=(256, 192), cam_size=(512, 384)))
    ang = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    uv = np.c_[128 + 60 * np.cos(ang), 96 + 60 * np.sin(ang)]
    sch = scheduling.dot_schedule(rig, uv, depth_range=(1.3, 2.0), min_proj_spacing=2.0)
    seg = dots.epipolar_segments(rig, uv, (1.3, 2.0))
    i, j = np.triu_indices(len(uv), 1)
    bad = _conflicts(seg, uv, i, j, 2.0, 6.0) & (sch.colour[i] == sch.colour[j])
    assert not bad.any()
    assert 3 <= sch.lower_bound <= len(sch.frames) < 40


def test_multiplexed_frames_decode_like_one_dot_frames(rig, rng):
    # plane z = 0 seen by the moonyard rig; render each frame as Gaussian camera spots
    k = 300
    proj_uv = np.floor(rng.uniform([0, 0], [128, 96], size=(k, 2))) + 0.5
    o, d = rig.projector.rays(proj_uv)
    X = o + (-o[:, 2:3] / d[:, 2:3]) * d
    cam_uv, _ = rig.camera.project(X)
    z = rig.projector.pose.world_to_device(X)[:, 2]
    rng_z = (z.min() * 0.95, z.max() * 1.05)

    def run(frames):
        found = np.full((k, 2), np.nan)
        for f in frames:
            img = gaussian_spots((120, 160), cam_uv[f], 0.9)
            det = dots.detect_dots(img, background=0.0)
            m = dots.match_dots(det, dots.epipolar_segments(rig, proj_uv[f], rng_z))
            found[f[m.dot]] = m.cam_uv
        return found

    multi = scheduling.schedule_dots(rig, proj_uv, depth_range=rng_z)
    exact = scheduling.schedule_dots(rig, proj_uv, depth_range=rng_z, exact=True)
    fm, fe = run(multi), run(exact)
    ok = np.isfinite(fm).all(1) & np.isfinite(fe).all(1)
    # spots within a few pixels of the image border are dropped (truncated centroids)
    inner = np.all((cam_uv > 4) & (cam_uv < np.array([160, 120]) - 4), axis=1)
    assert ok[inner].mean() > 0.95
    assert len(multi) * 5 < k
    assert np.median(np.linalg.norm(fm[ok] - fe[ok], axis=1)) < 0.01
    pts, _ = tri.triangulate_rays(rig, fm[ok], proj_uv[ok])
    assert np.median(np.abs(pts[:, 2])) < 1e-3  # back on the z = 0 plane (m)


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
