"""Triangulation round trips, epipolar geometry, depth resampling, rig presets and bad rigs."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, Pose, Projector, Rig
from simlunar.scanner import rigs
from simlunar.scanner import triangulate as tri


@pytest.fixture
def rig():
    return rigs.moonyard_rig(proj_size=(64, 48), cam_size=(80, 60))


def _random_scene_points(rig, rng, n=400):
    uv = rng.uniform([0, 0], [64, 48], size=(n, 2))
    z = rng.uniform(1.3, 1.9, size=n)
    return rig.projector.pose.device_to_world(rig.projector.directions_device(uv) * z[:, None])


def test_project_then_triangulate_rays_and_planes(rig, rng):
    X = _random_scene_points(rig, rng)
    cam_uv, _ = rig.camera.project(X)
    proj_uv, _ = rig.projector.project(X)
    pts, res = tri.triangulate_rays(rig, cam_uv, proj_uv)
    assert np.max(np.abs(pts - X)) < 1e-9
    assert np.max(res) < 1e-9
    pts_plane = tri.triangulate_plane(rig, cam_uv, proj_uv[:, 0])
    assert np.max(np.abs(pts_plane - X)) < 1e-9
    cloud = tri.triangulate(rig, tri.Correspondences(cam_uv, proj_uv), method="plane")
    assert len(cloud) == len(X)
    with pytest.raises(ValueError, match="valid: 'plane', 'rays'"):
        tri.triangulate(rig, tri.Correspondences(cam_uv, proj_uv), method="nope")


def test_fundamental_matrix_epipolar_constraint(rig, rng):
    X = _random_scene_points(rig, rng)
    cam_uv, _ = rig.camera.project(X)
    proj_uv, _ = rig.projector.project(X)
    F = tri.fundamental_matrix(rig)
    assert np.max(tri.epipolar_distance(F, cam_uv, proj_uv)) < 1e-8
    # shifting the camera point off the line by 3 px perpendicular to it gives distance 3
    xp = np.c_[proj_uv, np.ones(len(proj_uv))]
    line = xp @ F.T
    nrm = line[:, :2] / np.linalg.norm(line[:, :2], axis=1, keepdims=True)
    np.testing.assert_allclose(tri.epipolar_distance(F, cam_uv + 3 * nrm, proj_uv), 3.0, rtol=1e-9)
    assert np.linalg.matrix_rank(F, tol=1e-9 * np.abs(F).max()) == 2


def test_depth_in_view_and_at_projector_pixels(rig, rng):
    # points exactly on guide-pixel rays at known depths land in those pixels
    guide = rig.guide
    rc = np.array([[3, 4], [10, 20], [10, 20], [47, 63]])
    z = np.array([1.5, 1.6, 1.8, 1.7])
    uv = np.c_[rc[:, 1] + 0.5, rc[:, 0] + 0.5]
    pts = guide.pose.device_to_world(guide.directions_device(uv) * z[:, None])
    d = tri.depth_in_view(pts, guide)
    assert d.shape == (48, 64)
    assert np.count_nonzero(np.isfinite(d)) == 3
    np.testing.assert_allclose([d[3, 4], d[10, 20], d[47, 63]], [1.5, 1.7, 1.7])
    assert tri.depth_in_view(pts, guide, reduce="min")[10, 20] == pytest.approx(1.6)
    cloud = tri.PointCloud(pts, uv, np.zeros(4))
    np.testing.assert_allclose(tri.depth_at_proj_pixels(cloud, guide)[10, 20], 1.7)
    with pytest.raises(ValueError, match="reduce"):
        tri.depth_in_view(pts, guide, reduce="median")


def test_true_correspondences_and_visibility(rig):
    guide = rig.guide
    depth = np.full((48, 64), 1.6)
    depth[5:10, 7:12] = 1.2  # an occluder in front of a 5 x 5 pixel patch
    pts = guide.unproject_depth(np.full((48, 64), 1.6))
    col, row = tri.true_correspondences(pts, rig.projector)
    np.testing.assert_array_equal(col, np.broadcast_to(np.arange(64), (48, 64)))
    np.testing.assert_array_equal(row, np.broadcast_to(np.arange(48)[:, None], (48, 64)))
    lit = tri.projector_visibility(pts, rig.projector, depth)
    # the 3 x 3 window keeps a one-pixel rim of the shadow lit: 3 x 3 pixels stay dark
    assert lit.sum() == 48 * 64 - 9 and not lit[6:9, 8:11].any()
    col2, _ = tri.true_correspondences(pts, rig.projector, lit=lit)
    assert col2[7, 9] == -1
    assert tri.projector_visibility(pts, rig.projector, depth, window=1).sum() == 48 * 64 - 25


def test_zero_baseline_and_off_centre_projector_are_rejected():
    K = Intrinsics.from_fov(64, 48, 40.0)
    pose = Pose.look_at((0, 0, 2.0), (0, 0, 0))
    with pytest.raises(ValueError, match="baseline is zero"):
        Rig(Projector(K, pose), Camera(K, pose))
    with pytest.raises(ValueError, match="baseline is zero"):
        rigs.moonyard_rig(baseline=0.0)
    with pytest.raises(ValueError, match="principal point must be centred"):
        Projector(Intrinsics(50.0, 50.0, 30.0, 24.0, 64, 48), pose)


def test_rig_presets_see_their_target():
    for name in ("moonyard", "aerial"):
        r = rigs.rig_preset(name, proj_size=(64, 48), cam_size=(80, 60))
        # the optical axis meets the z = 0 target plane here
        target = r.projector.position + r.projector.pose.forward * (
            (0.0 - r.projector.position[2]) / r.projector.pose.forward[2]
        )
        uv, z = r.camera.project(target)
        assert z > 0 and 0 <= uv[0] < 80 and 0 <= uv[1] < 60
        # the guide camera is the projector
        np.testing.assert_array_equal(r.guide.position, r.projector.position)
    assert rigs.aerial_rig().projector.pose.forward == pytest.approx([0, 0, -1])
    assert rigs.footprint(rigs.aerial_rig(), 100.0) == pytest.approx(
        100.0 * 2 * np.tan(np.radians(15)) / 1024
    )
    with pytest.raises(ValueError, match=r"valid: \['aerial', 'moonyard'\]"):
        rigs.rig_preset("orbital")
