import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, OrthoCamera, Pose, Projector, Rig


def test_look_at_axes_follow_opencv_convention():
    # Looking north (+y) from the origin: image right is east (+x), image down is -z.
    p = Pose.look_at([0, 0, 0], [0, 1, 0])
    np.testing.assert_allclose(p.rotation[:, 0], [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(p.rotation[:, 1], [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(p.rotation[:, 2], [0, 1, 0], atol=1e-12)
    # straight down: north (+y) is image up
    p = Pose.look_at([0, 0, 10], [0, 0, 0])
    np.testing.assert_allclose(p.rotation[:, 1], [0, -1, 0], atol=1e-12)


def test_project_then_ray_round_trip(rng):
    K = Intrinsics(500.0, 520.0, 321.3, 239.7, 640, 480)
    cam = Camera(K, Pose.look_at([1, -2, 5], [0.2, 0.1, 0]))
    pts = rng.uniform(-1, 1, (100, 3)) * [1, 1, 0.2]
    uv, z = cam.project(pts)
    assert np.all(z > 0)
    o, d = cam.rays(uv)
    # the point lies on its ray: distance from the ray is zero
    v = pts - o
    perp = v - np.sum(v * d, axis=-1, keepdims=True) * d
    np.testing.assert_allclose(np.linalg.norm(perp, axis=-1), 0, atol=1e-9)


def test_principal_point_pixel_centres():
    K = Intrinsics.from_fov(4, 2, 90.0)
    assert (K.cx, K.cy) == (2.0, 1.0) and K.fx == pytest.approx(2.0)
    cam = Camera(K, Pose.look_at([0, 0, 1], [0, 0, 0]))
    uv, _ = cam.project(np.array([[0.0, 0.0, 0.0]]))
    np.testing.assert_allclose(uv, [[2.0, 1.0]])  # the corner shared by the 4 central pixels
    np.testing.assert_allclose(K.to_opencv()[:2, 2], [1.5, 0.5])


def test_unproject_depth_inverts_project(rng):
    cam = Camera(Intrinsics.from_fov(8, 6, 60.0), Pose.look_at([0, 0, 3], [0, 0, 0]))
    depth = rng.uniform(1, 2, (6, 8))
    X = cam.unproject_depth(depth)
    uv, z = cam.project(X)
    np.testing.assert_allclose(z, depth, atol=1e-12)
    np.testing.assert_allclose(uv, cam.pixel_centers(), atol=1e-9)


def test_nadir_ortho_pixel_is_dem_cell():
    cam = OrthoCamera.nadir_for_grid((3, 5), 0.2, origin=(10.0, 20.0), altitude=50.0)
    o, d = cam.rays(cam.pixel_centers())
    np.testing.assert_allclose(d, np.broadcast_to([0, 0, -1.0], d.shape), atol=1e-12)
    # cell (r, c) centre = (x0 + (c + .5) s, y0 - (r + .5) s)
    np.testing.assert_allclose(o[1, 3, :2], [10.0 + 3.5 * 0.2, 20.0 - 1.5 * 0.2])
    uv, _ = cam.project(o[2, 4])
    np.testing.assert_allclose(uv, [4.5, 2.5])


def test_bad_input_is_rejected():
    with pytest.raises(ValueError, match="principal point must be centred"):
        Projector(Intrinsics(100, 100, 30, 20, 64, 48), Pose.look_at([0, 0, 1], [0, 0, 0]))
    pose = Pose.look_at([0, 0, 1], [0, 0, 0])
    proj = Projector(Intrinsics.from_fov(64, 48, 40), pose)
    with pytest.raises(ValueError, match="baseline is zero"):
        Rig(proj, Camera(proj.intrinsics, pose))
    with pytest.raises(ValueError, match="focal lengths"):
        Intrinsics(0, 1, 0, 0, 1, 1)
    with pytest.raises(ValueError, match="orthonormal"):
        Pose(np.eye(3) * 2, np.zeros(3))


def test_rig_guide_is_colocated():
    proj = Projector(Intrinsics.from_fov(64, 48, 40), Pose.look_at([0, 0, 1], [0, 0, 0]))
    cam = Camera(Intrinsics.from_fov(80, 60, 45), Pose.look_at([0.3, 0, 1], [0, 0, 0]))
    rig = Rig(proj, cam)
    assert rig.baseline == pytest.approx(0.3)
    np.testing.assert_array_equal(rig.guide.position, proj.position)
    assert rig.guide.intrinsics == proj.intrinsics
