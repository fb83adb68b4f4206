"""The platform's trajectory."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar.trajectory import Trajectory


def test_hover_and_descent_by_hand():
    h = Trajectory.hover([1.0, 2.0, 50.0])
    assert h.at([0.0, 10.0]) == pytest.approx(np.array([[1.0, 2.0, 50.0]] * 2))
    d = Trajectory.descent([0.0, 0.0, 50.0], 2.0, horizontal_m_s=(0.5, 0.0))
    assert d.at(3.0) == pytest.approx([1.5, 0.0, 44.0])
    assert d.at(np.zeros((2, 4))).shape == (2, 4, 3)


def test_bad_trajectory():
    with pytest.raises(ValueError, match="position_m must be 3 finite numbers"):
        Trajectory((0.0, np.nan, 1.0))


def test_attitude_jitter_is_stationary_with_its_rms():
    from simlunar.lidar.trajectory import JITTER_TONES

    t = np.linspace(0.0, 200.0, 200_001)
    tr = Trajectory((0, 0, 50.0), attitude_jitter_rad=1e-3, jitter_bandwidth_hz=5.0)
    w = tr.attitude_at(t)
    assert w.shape == (t.size, 3)
    # each axis a sum of JITTER_TONES sinusoids of amplitude sigma sqrt(2 / M): RMS = sigma
    assert JITTER_TONES >= 4
    assert np.sqrt((w**2).mean(axis=0)) == pytest.approx([1e-3] * 3, rel=0.05)
    assert np.abs(w.mean(axis=0)).max() < 1e-4
    assert tr.attitude_at([0.0, 1.0]) == pytest.approx(tr.attitude_at([0.0, 1.0]))  # seeded
    assert not np.allclose(Trajectory((0, 0, 1), attitude_jitter_rad=1e-3, jitter_seed=1)
                           .attitude_at(1.0), tr.attitude_at(1.0))  # fmt: skip
    assert Trajectory.hover((0, 0, 1)).attitude_at([1.0, 2.0]) == pytest.approx(np.zeros((2, 3)))


def test_rotate_small_matches_rodrigues_by_hand():
    from simlunar.lidar.trajectory import rotate_small

    # 90 deg about z turns x into y; a zero rotation changes nothing
    v = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    w = np.array([[0.0, 0.0, np.pi / 2], [0.0, 0.0, 0.0]])
    assert rotate_small(v, w) == pytest.approx(np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]))
    # a small rotation about x of 1e-3 tilts +z towards -y by 1e-3
    assert rotate_small(np.array([[0.0, 0.0, 1.0]]), np.array([[1e-3, 0.0, 0.0]]))[0] == (
        pytest.approx([0.0, -np.sin(1e-3), np.cos(1e-3)])
    )


def test_place_points_round_trip_and_its_compensations():
    from simlunar.lidar.trajectory import Navigation, place_points, rotate_small

    rng = np.random.default_rng(0)
    tr = Trajectory.descent((0.0, 0.0, 50.0), 2.0, (0.5, 0.0), attitude_jitter_rad=2e-3)
    t = np.linspace(0.0, 10.0, 50)
    cmd = np.column_stack([rng.normal(0, 0.2, (50, 2)), -np.ones(50)])
    cmd /= np.linalg.norm(cmd, axis=1, keepdims=True)
    fired = rotate_small(cmd, tr.attitude_at(t))
    pos = tr.at(t)
    r = (pos[:, 2] - 0.0) / -fired[:, 2]  # the plane z = 0
    truth = pos + r[:, None] * fired
    exact = place_points(r, cmd, t, tr)
    assert exact == pytest.approx(truth, abs=1e-9)
    start = place_points(r, cmd, t, tr, Navigation("start"))
    assert np.abs(start[:, 2]).max() > 10.0  # 20 m of descent ignored
    noisy = place_points(r, cmd, t, tr, Navigation("noisy", 0.1, 0.0), rng=1)
    err = noisy - truth
    assert np.sqrt((err**2).mean()) == pytest.approx(0.1, rel=0.3)
    with pytest.raises(
        ValueError, match="compensation must be one of 'exact', 'noisy', 'start', got 'perfect'"
    ):
        Navigation("perfect")
    with pytest.raises(ValueError, match="attitude_jitter_rad"):
        Trajectory((0, 0, 1.0), attitude_jitter_rad=-1.0)


def test_camera_at_carries_a_device_to_the_pose_at_a_time():
    from simlunar.geometry import Camera, Intrinsics, Pose
    from simlunar.lidar.trajectory import camera_at, rotate_small

    cam = Camera(
        Intrinsics.from_fov(16, 16, 10.0),
        Pose.look_at([5.0, 5.0, 99.0], [5.0, 5.0, 0.0], up=(0.0, 1.0, 0.0)),
    )
    # a 4 m/s descent with 1 m/s drift from (0, 0, 50): at 2.5 s at (2.5, 0, 40); the camera's
    # own position is replaced, its orientation kept without jitter
    tr = Trajectory.descent((0.0, 0.0, 50.0), 4.0, horizontal_m_s=(1.0, 0.0))
    moved = camera_at(cam, tr, 2.5)
    assert moved.position == pytest.approx([2.5, 0.0, 40.0])
    assert moved.pose.rotation == pytest.approx(cam.pose.rotation, abs=1e-15)
    assert moved.intrinsics == cam.intrinsics
    # with jitter every axis (and so every pixel's ray) turns by the jitter's rotation then
    jt = Trajectory((0.0, 0.0, 50.0), attitude_jitter_rad=2e-3, jitter_seed=3)
    turned = camera_at(cam, jt, 0.7)
    w = jt.attitude_at(0.7)
    assert np.linalg.norm(w) > 1e-4
    uv = np.array([[0.5, 0.5], [8.0, 8.0], [15.5, 3.5]])
    before = cam.rays(uv)[1]
    after = turned.rays(uv)[1]
    assert after == pytest.approx(rotate_small(before, np.broadcast_to(w, before.shape)), abs=1e-12)


def test_a_scan_that_outlasts_the_descent_is_refused_naming_when():
    # 100 m up at 2 m/s down: 0.1 m above the datum at 49.95 s; beams at 0, 10 and 49.9 s
    # clear it, one at 49.96 s does not (0.08 m) and is named
    from simlunar.errors import PlatformGroundedError
    from simlunar.lidar.trajectory import check_airborne

    t = Trajectory(position_m=(0.0, 0.0, 100.0), velocity_m_s=(0.0, 0.0, -2.0))
    check_airborne(t, [0.0, 10.0, 49.9], 0.0, 0.1)
    with pytest.raises(PlatformGroundedError, match=r"0.1 m of the ground .* 50 s into a 60 s"):
        check_airborne(t, [0.0, 10.0, 49.96, 60.0], 0.0, 0.1)
    # a datum above the start: grounded at once
    with pytest.raises(PlatformGroundedError, match="0 s into"):
        check_airborne(t, [0.0], 150.0, 0.1)
    check_airborne(t, [], 0.0, 0.1)  # nothing fired, nothing to refuse
