"""Frame conversion OpenCV <-> Mitsuba: sensor rays must equal the pinhole model's rays."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, OrthoCamera, Pose
from simlunar.render.cameras import principal_point_offsets, sensor_dict, to_world_matrix

pytestmark = pytest.mark.render


def _sensor_rays(mi, camera, uv):
    sensor = mi.load_dict(sensor_dict(camera, spp=1))
    w, h = (
        (camera.intrinsics.width, camera.intrinsics.height)
        if isinstance(camera, Camera)
        else (camera.width, camera.height)
    )
    n = len(uv)
    ray, _ = sensor.sample_ray(
        mi.Float(np.zeros(n)),
        mi.Float(np.full(n, 0.5)),
        mi.Point2f(uv[:, 0] / w, uv[:, 1] / h),
        mi.Point2f(np.full(n, 0.5), np.full(n, 0.5)),
    )
    # a constant (orthographic) direction comes back as a single entry: broadcast it
    o = np.broadcast_to(np.array(ray.o, np.float64).reshape(3, -1).T, (n, 3))
    d = np.broadcast_to(np.array(ray.d, np.float64).reshape(3, -1).T, (n, 3))
    return o, d


def test_perspective_rays_match_pinhole_model_off_centre(mi, rng):
    # off-centre principal point and a tilted pose: any axis flip or half-pixel shift shows
    K = Intrinsics(50.0, 50.0, 23.7, 13.2, 40, 30)
    cam = Camera(K, Pose.look_at([1.0, -2.0, 3.0], [0.2, 0.5, 0.0]))
    uv = np.column_stack([rng.uniform(0, 40, 50), rng.uniform(0, 30, 50)])
    uv = np.vstack([uv, [[0.5, 0.5], [39.5, 0.5], [0.5, 29.5], [23.7, 13.2]]])
    o, d = _sensor_rays(mi, cam, uv)
    _, d_ref = cam.rays(uv)
    np.testing.assert_allclose(d, d_ref, atol=2e-6)
    # Mitsuba starts rays on the near plane, on the line through the centre of projection
    np.testing.assert_allclose(np.cross(o - cam.position, d_ref), 0.0, atol=1e-6)


def test_orthographic_rays_match_model(mi):
    cam = OrthoCamera.nadir_for_grid((6, 8), 0.5, origin=(10.0, 20.0), altitude=50.0)
    uv = cam.pixel_centers().reshape(-1, 2)
    o, d = _sensor_rays(mi, cam, uv)
    o_ref, d_ref = cam.rays(uv)
    np.testing.assert_allclose(d, d_ref, atol=1e-6)
    # same x, y (z is offset by the near clip along the view direction)
    np.testing.assert_allclose(o[:, :2], o_ref[:, :2], atol=1e-4)
    # pixel (r, c) of the nadir camera is above cell (r, c): x0 + (c + .5) s, y0 - (r + .5) s
    np.testing.assert_allclose(o[0, :2], [10.25, 19.75], atol=1e-4)
    np.testing.assert_allclose(o[-1, :2], [10.0 + 7.5 * 0.5, 20.0 - 5.5 * 0.5], atol=1e-4)


def test_principal_point_offset_convention():
    K = Intrinsics(10.0, 10.0, 2.0, 4.5, 8, 6)
    cam = Camera(K, Pose(np.eye(3), np.zeros(3)))
    # hand-computed: (8/2 - 2)/8 = 0.25, (6/2 - 4.5)/6 = -0.25
    assert principal_point_offsets(cam) == pytest.approx((0.25, -0.25))


def test_to_world_is_a_proper_rotation_with_flipped_x_y():
    pose = Pose.look_at([0, 0, 5.0], [1.0, 2.0, 0.0])
    m = to_world_matrix(pose)
    R = m[:3, :3]
    assert np.linalg.det(R) == pytest.approx(1.0)
    np.testing.assert_allclose(R[:, 0], -pose.rotation[:, 0])
    np.testing.assert_allclose(R[:, 1], -pose.rotation[:, 1])
    np.testing.assert_allclose(R[:, 2], pose.rotation[:, 2])
    np.testing.assert_allclose(m[:3, 3], pose.position)


def test_thin_lens_dict(mi):
    K = Intrinsics.from_fov(16, 12, 40.0)
    cam = Camera(K, Pose.look_at([0, 0, 5.0], [0, 0, 0]), aperture_radius=0.01, focus_distance=5.0)
    d = sensor_dict(cam)
    assert d["type"] == "thinlens"
    assert d["aperture_radius"] == 0.01 and d["focus_distance"] == 5.0
    mi.load_dict(d)


def test_thin_lens_off_centre_is_rejected(mi):
    K = Intrinsics(20.0, 20.0, 7.0, 6.0, 16, 12)
    cam = Camera(K, Pose.look_at([0, 0, 5.0], [0, 0, 0]), aperture_radius=0.01, focus_distance=5.0)
    with pytest.raises(ValueError, match="principal point"):
        sensor_dict(cam)


def test_non_square_pixels_rejected(mi):
    cam = Camera(Intrinsics(20.0, 25.0, 8.0, 6.0, 16, 12), Pose(np.eye(3), np.zeros(3)))
    with pytest.raises(ValueError, match=r"fx=20\.0 != fy=25\.0"):
        sensor_dict(cam)


def test_unknown_camera_type(mi):
    with pytest.raises(ValueError, match="camera: unknown camera type str"):
        sensor_dict("orthographic")
