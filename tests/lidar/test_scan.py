"""Steered-beam LIDAR end to end on a plane: ranges, ordering and timing, a gate that never reads
the truth, a moving platform, SPAD pile-up; flash LIDARs: test_flash_lidar.py."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import (
    DetectorOptions,
    FootprintOptions,
    OrderOptions,
    PulseOptions,
    SteeringOptions,
    scan_timing,
)
from simlunar.terrain import Terrain
from tests.render._lidar_planes import DET, H, _camera, _plane

pytestmark = pytest.mark.render


def test_steered_beam_scan_on_a_plane(mi):
    from simlunar.lidar.scan import SteeredBeamOptions, steered_beam_scan
    from simlunar.render.beam_capture import beam_capture

    steer = SteeringOptions(
        max_rate_rad_s=1.0,
        max_accel_rad_s2=10.0,
        settle_s=1e-3,
        pulse_rate_hz=1000.0,
        pulses_per_point=4,
    )
    opts = SteeredBeamOptions(
        footprint=FootprintOptions(5e-4, samples=8),
        pulse=PulseOptions(fwhm_s=1e-9),
        detector=DET,
        steering=steer,
        window_m=4.0,
        margin_m=1.0,
        batch=32,
    )
    cam = _camera(64, 40.0)
    uv = np.random.default_rng(0).uniform(0, 64, (50, 2))
    from simlunar.lidar.scan import guide_directions

    d = guide_directions(cam, uv[:, ::-1] - 0.5)  # the same rays, from (row, col)
    assert d == pytest.approx(cam.rays(uv)[1])
    scan = steered_beam_scan(
        beam_capture(_plane(), cam.position, options=opts),
        d,
        options=opts,
        rng=1,
        boresight=cam.pose,
    )
    truth = H / -d[:, 2]
    assert scan.valid.all()
    assert np.abs(scan.ranges - truth).max() < opts.bin_range_m
    assert scan.points[:, 2] == pytest.approx(0.0, abs=opts.bin_range_m)
    assert scan.depth(cam) == pytest.approx(H, abs=opts.bin_range_m)  # nadir view of z = 0
    from simlunar.lidar import pointing_angles

    ang = pointing_angles(d, cam.pose)
    assert sorted(scan.order) == list(range(50))
    assert scan.seconds == pytest.approx(scan_timing(ang, scan.order, options=steer).total_s)
    assert scan.seconds <= scan_timing(ang, options=steer).total_s
    assert scan.frames == 200
    raster = steered_beam_scan(
        beam_capture(_plane(), cam.position, options=opts),
        d,
        rng=1,
        boresight=cam.pose,
        options=SteeredBeamOptions(**{**opts.__dict__, "order": OrderOptions(method="raster")}),
    )
    assert scan.seconds < raster.seconds


def _truth_raises(monkeypatch):
    """Every way to the terrain's truth after the scene is built raises."""
    from simlunar.render.beam_capture import BeamCapture

    def boom(*args, **kwargs):
        raise AssertionError("the range gate read the terrain's truth")

    monkeypatch.setattr(BeamCapture, "cast", boom)
    monkeypatch.setattr(Terrain, "points", boom)


@pytest.mark.parametrize("altimeter", [False, True])
def test_steered_gate_never_reads_the_truth(mi, monkeypatch, altimeter):
    from simlunar.lidar.gate import GateOptions
    from simlunar.lidar.scan import SteeredBeamOptions, steered_beam_scan
    from simlunar.render.beam_capture import beam_capture

    opts = SteeredBeamOptions(
        footprint=FootprintOptions(5e-4, samples=4),
        pulse=PulseOptions(fwhm_s=1e-9),
        detector=DET,
        window_m=4.0,
        margin_m=1.0,
        batch=16,
        gate=GateOptions(altimeter=altimeter, max_range_m=200.0),
    )
    cam = _camera(32, 30.0)
    cap = beam_capture(_plane(), cam.position, options=opts)
    _truth_raises(monkeypatch)
    rc = np.array([[4, 4], [16, 16], [28, 3], [10, 25]])
    from simlunar.lidar.scan import guide_directions

    d = guide_directions(cam, rc)
    scan = steered_beam_scan(cap, d, options=opts, rng=0, boresight=cam.pose)
    assert scan.valid.all()
    assert scan.points[:, 2] == pytest.approx(0.0, abs=0.025)  # 4.5 mm CRLB at 200 photons
    if altimeter:  # 50 m in windows of 4 m stepped by 2 m from 0.1 m: found in step 24-26
        p = opts.steering.pulses_per_point
        assert (4 + 24) * p <= scan.frames <= (4 + 26) * p


def test_a_descending_platform_s_cloud_lands_on_the_terrain(mi):
    # a tilted plane (z = 0.3 x) scanned while descending at 4 m/s and drifting 1 m/s east: the
    # scan takes about 2 s (slow gimbal), the platform falls about 8 m. With each beam leaving
    # from the platform's position at its firing time (the pose known exactly) every point
    # lies on the plane; the same ranges placed from the starting pose miss it by metres.
    from simlunar.lidar.scan import SteeredBeamOptions, guide_directions, steered_beam_scan
    from simlunar.lidar.trajectory import Trajectory
    from simlunar.render.beam_capture import beam_capture

    n = 80
    x = -n / 2 + np.arange(n) + 0.5
    plane = Terrain(
        heights=np.broadcast_to(0.3 * x[None, :], (n, n)).copy(),
        albedo=np.full((n, n), 0.2, np.float32),
        spacing=1.0,
        origin=(-n / 2, n / 2),
    )
    steer = SteeringOptions(max_rate_rad_s=0.5, max_accel_rad_s2=5.0, settle_s=0.05,
                            pulse_rate_hz=1000.0, pulses_per_point=4)  # fmt: skip
    opts = SteeredBeamOptions(
        footprint=FootprintOptions(2e-4, samples=4),
        pulse=PulseOptions(fwhm_s=1e-9),
        detector=DET,
        steering=steer,
        window_m=8.0,
        margin_m=3.0,  # the plane's relief about z = 0 within the field: +-5 m across, ~3 m
        batch=16,
    )
    cam = _camera(32, 30.0)
    traj = Trajectory.descent(cam.position, 4.0, horizontal_m_s=(1.0, 0.0))
    cap = beam_capture(plane, cam.position, options=opts)
    rc = np.random.default_rng(2).integers(4, 28, (24, 2))
    d = guide_directions(cam, rc)
    scan = steered_beam_scan(cap, d, options=opts, rng=0, boresight=cam.pose, trajectory=traj)
    assert scan.seconds > 1.5 and scan.times.max() > 1.5
    assert scan.valid.mean() > 0.9
    p = scan.points[scan.valid]
    assert p[:, 2] == pytest.approx(0.3 * p[:, 0], abs=0.03)
    # control: the same ranges from the starting pose
    still = cam.position + scan.ranges[scan.valid, None] * d[scan.valid]
    assert np.abs(still[:, 2] - 0.3 * still[:, 0]).max() > 1.0
    # with 2 mrad of line-of-sight jitter, retargeted beams: placed with the known pose (the
    # jitter included) the cloud still lies on the plane; without motion compensation
    # ("start") it does not
    from simlunar.lidar.trajectory import Navigation

    jit = Trajectory.descent(cam.position, 4.0, horizontal_m_s=(1.0, 0.0),
                             attitude_jitter_rad=2e-3, jitter_bandwidth_hz=2.0)  # fmt: skip
    for nav, on_plane in ((Navigation("exact"), True), (Navigation("start"), False)):
        s2 = steered_beam_scan(cap, d, options=opts, rng=0, boresight=cam.pose, trajectory=jit,
                               navigation=nav)  # fmt: skip
        assert s2.valid.mean() > 0.9
        q = s2.points[s2.valid]
        miss = np.abs(q[:, 2] - 0.3 * q[:, 0])
        assert (miss.max() < 0.03) if on_plane else (miss.max() > 1.0)


@pytest.mark.parametrize("correct", [True, False])
def test_spad_scan_pile_up_and_its_correction(mi, correct):
    # 30 signal photons per pulse on a SPAD with a 1.5 ns dead time: the raw reading is early
    # (the first photon arrives on the pulse's leading edge); the scans' refit removes it
    from simlunar.lidar import RangeOptions
    from simlunar.lidar.scan import SteeredBeamOptions, steered_beam_scan
    from simlunar.render.beam_capture import beam_capture

    det = DetectorOptions(signal_photons=2e6 * 30 / 51, background_photons_per_s=0.0,
                          dead_time_s=1.5e-9)  # fmt: skip
    opts = SteeredBeamOptions(
        footprint=FootprintOptions(1e-5, samples=4),
        pulse=PulseOptions(fwhm_s=1e-9, jitter_s=0.1e-9),
        detector=det,
        ranging=RangeOptions(pileup_correction=correct),
        steering=SteeringOptions(pulses_per_point=400),
        window_m=4.0,
        margin_m=1.0,
        batch=8,
    )
    cap = beam_capture(_plane(), [0.0, 0.0, H], options=opts)
    d = np.tile([[0.0, 0.0, -1.0]], (6, 1))
    scan = steered_beam_scan(cap, d, options=opts, rng=3)
    err = scan.ranges - H
    assert scan.valid.all()
    if correct:  # scatter about 3 mm: a piled-up pulse keeps 1-2 detections of its 30 photons
        assert abs(err.mean()) < 0.003 and np.abs(err).max() < 0.01
        # the signal per pulse, 30 (0.2 / (pi 50^2) x the scale), +-25 % per beam at 400 pulses
        assert np.mean(scan.photons / 400) == pytest.approx(30.0, rel=0.1)
    else:
        assert err.mean() < -0.02
