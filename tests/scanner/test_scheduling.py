"""Dot scheduling (simlunar/scanner/scheduling.py): hand cases of which dots may share a frame,
the frames against the exact conflict test on several rigs, optimality on one epipolar line, the
lower bound, and the input checks."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import dots, rigs, scheduling
from simlunar.scanner import triangulate as tri
from tests.scanner.test_dots import gaussian_spots


@pytest.fixture
def rig():
    return rigs.moonyard_rig(proj_size=(128, 96), cam_size=(160, 120))


# --- hand cases ---------------------------------------------------------------------------------


def test_check_spacings_accepts_positive_and_names_both_values():
    scheduling.check_spacings(6.0, 8.0)
    scheduling.check_spacings(1e-6, 1)
    for cam, proj in [(0.0, 8.0), (6.0, -1.0), (float("inf"), 8.0), (6.0, float("nan"))]:
        with pytest.raises(ValueError, match=rf"must be > 0 px, got {cam} and {proj}"):
            scheduling.check_spacings(cam, proj)


def test_dot_schedule_checks_the_spacings_and_the_dots(rig):
    with pytest.raises(ValueError, match=r"min_cam_spacing and min_proj_spacing must be > 0 px"):
        scheduling.dot_schedule(rig, [[10.5, 10.5]], depth_range=(1.4, 1.8), min_cam_spacing=0)
    with pytest.raises(ValueError, match="empty"):
        scheduling.dot_schedule(rig, np.empty((0, 2)), depth_range=(1.4, 1.8))


def test_schedule_properties_by_hand():
    # three frames over a clique of two: the bound is 2, frames over bound 1.5; an empty clique
    # (bound=False) divides by 1, not 0
    frames = [np.array([0, 3]), np.array([1]), np.array([2])]
    colour = np.array([0, 1, 2, 0])
    s = scheduling.DotSchedule(frames=frames, colour=colour, clique=np.array([0, 1]))
    assert s.lower_bound == 2 and s.frames_over_bound == 1.5
    s0 = scheduling.DotSchedule(frames=frames, colour=colour, clique=np.empty(0, np.int64))
    assert s0.lower_bound == 0 and s0.frames_over_bound == 3.0


def test_two_dots_share_a_frame_iff_far_apart_in_projector_and_camera():
    # parallel rig (rectified rows): dots on projector rows 20 and 150 map to camera rows far
    # apart, so they share one frame; 4 projector px apart (< min_proj_spacing 8) on one row they
    # conflict and need two frames, and the pair is the lower bound
    rig = rigs.moonyard_rig(proj_size=(256, 192), cam_size=(512, 384), verge=False)
    kw = {"depth_range": (1.3, 2.0), "min_proj_spacing": 8.0, "min_cam_spacing": 6.0}
    far = scheduling.dot_schedule(rig, [[10.5, 20.5], [200.5, 150.5]], **kw)
    assert [f.tolist() for f in far.frames] == [[0, 1]]
    assert far.colour.tolist() == [0, 0] and far.lower_bound == 1
    near = scheduling.dot_schedule(rig, [[100.5, 50.5], [104.5, 50.5]], **kw)
    assert sorted(f.tolist() for f in near.frames) == [[0], [1]]
    assert sorted(near.clique.tolist()) == [0, 1] and near.lower_bound == 2
    # 4 projector px apart but a spacing of 3: only the camera segments decide. On one camera
    # row the two segments overlap along the row (the depth range smears each over many
    # pixels), so they still conflict
    seg = dots.epipolar_segments(rig, [[100.5, 50.5], [104.5, 50.5]], (1.3, 2.0))
    assert dots.segment_distance(seg[0], seg[1]) < 6.0
    near3 = scheduling.dot_schedule(
        rig, [[100.5, 50.5], [104.5, 50.5]], **{**kw, "min_proj_spacing": 3.0}
    )
    assert len(near3.frames) == 2


def test_exact_mode_is_one_dot_per_frame_in_order(rig):
    uv = [[10.5, 10.5], [90.5, 70.5], [40.5, 30.5]]
    frames = scheduling.schedule_dots(rig, uv, depth_range=(1.4, 1.8), exact=True)
    assert [f.tolist() for f in frames] == [[0], [1], [2]]


def test_frames_are_the_colour_classes_in_colour_order(rig, rng):
    # guards _frames_from_colour: frame k holds exactly the dots of colour k, ascending
    proj_uv = rng.uniform([0, 0], [128, 96], size=(200, 2))
    sch = scheduling.dot_schedule(rig, proj_uv, depth_range=(1.4, 1.8))
    assert sch.colour.min() == 0 and len(sch.frames) == sch.colour.max() + 1
    for k, f in enumerate(sch.frames):
        np.testing.assert_array_equal(f, np.flatnonzero(sch.colour == k))
    # deterministic: no randomness in the schedule
    again = scheduling.dot_schedule(rig, proj_uv, depth_range=(1.4, 1.8))
    np.testing.assert_array_equal(again.colour, sch.colour)
    np.testing.assert_array_equal(again.clique, sch.clique)


# --- moved from test_dots.py ----------------------------------------------------------------------


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
