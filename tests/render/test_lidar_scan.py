"""LIDAR acquisitions end to end on a plane: steered beam, flash, micromirror flash."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar import (
    DetectorOptions,
    FootprintOptions,
    OrderOptions,
    PulseOptions,
    SteeringOptions,
    scan_timing,
)
from simlunar.terrain import Terrain

pytestmark = pytest.mark.render

H = 50.0
# about 50 signal photons per pulse from the plane at 50 m (rendered L = 0.2 / (pi R^2))
DET = DetectorOptions(signal_photons=2e6, background_photons_per_s=0.0, pulses=4)


def _plane(size: float = 80.0) -> Terrain:
    n = int(size)
    return Terrain(
        heights=np.zeros((n, n)),
        albedo=np.full((n, n), 0.2, np.float32),
        spacing=1.0,
        origin=(-size / 2, size / 2),
    )


def _camera(px: int, fov_deg: float) -> Camera:
    pose = Pose.look_at([0.0, 0.0, H], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    return Camera(Intrinsics.from_fov(px, px, fov_deg), pose)


def test_steered_beam_scan_on_a_plane(mi):
    from simlunar.render.lidar_scan import SteeredBeamOptions, beam_capture, steered_beam_scan

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
    from simlunar.render.lidar_scan import guide_directions

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


def test_flash_scan_on_a_plane(mi):
    from simlunar.render.lidar_scan import FlashOptions, flash_scan
    from simlunar.render.transient import TransientOptions

    cam = _camera(16, 4.0)
    opts = FlashOptions(
        detector=DET,
        pulse=PulseOptions(fwhm_s=1e-9),
        transient=TransientOptions(spp=8),
        pulse_rate_hz=20.0,
    )
    scan = flash_scan(_plane(), cam, options=opts, rng=0)
    assert scan.ranges.shape == (16, 16)
    d = cam.rays(cam.pixel_centers())[1]
    assert scan.valid.all()
    assert np.abs(scan.ranges - H / -d[..., 2]).max() < opts.bin_range_m
    assert scan.seconds == pytest.approx(4 / 20.0)
    from simlunar.render.lidar_scan import receiver_rc

    # a 16 x 16 receiver on a 64 x 64 guide: receiver pixel (0, 0) centre = guide (2, 2) - 1/2
    rc = receiver_rc((16, 16), (64, 64))
    assert rc[0] == pytest.approx([1.5, 1.5]) and rc[17] == pytest.approx([5.5, 5.5])


def test_micromirror_flash_lights_only_the_planned_pixels(mi):
    from simlunar.render.lidar_scan import FlashOptions, micromirror_flash, micromirror_frames
    from simlunar.render.transient import TransientOptions

    cam = _camera(32, 6.0)
    uv = np.array([[3.5, 3.5], [2.5, 2.5], [20.5, 9.5], [30.5, 30.5], [12.5, 27.5]])
    # receiver 8 x 8: the first two dots share receiver pixel (0, 0)
    assert list(micromirror_frames(uv, cam, (8, 8))) == [0, 1, 0, 0, 0]
    det = DetectorOptions(signal_photons=2e6 * 16, background_photons_per_s=0.0, pulses=4)
    opts = FlashOptions(
        detector=det,
        pulse=PulseOptions(fwhm_s=1e-9),
        transient=TransientOptions(spp=256),
        pulse_rate_hz=20.0,
    )
    scan = micromirror_flash(_plane(), cam, uv, options=opts, receiver_shape=(8, 8), rng=0)
    d = cam.rays(uv)[1]
    assert scan.frames == 2
    assert scan.seconds == pytest.approx(2 * 4 / 20.0)
    assert scan.valid.all()
    assert np.abs(scan.ranges - H / -d[:, 2]).max() < opts.bin_range_m


def test_flash_photons_follow_the_lidar_equation_per_pixel(mi):
    # a 16 x 16 flash over a 30 deg field lights a Lambertian plane (albedo 0.2) from 50 m:
    # every pixel's expected signal photons = (E / h nu) (rho / pi) cos(theta) A / R^2 eta
    # x Omega_pix / Omega_lit, with R = H / cos(theta) along the pixel's centre ray and
    # Omega_pix its exact solid angle (corner pixels dimmer as cos^3)
    from simlunar.lidar import TimeBins
    from simlunar.lidar.hardware import LidarHardware
    from simlunar.render.lidar_scan import FlashOptions, receiver_solid_angles, with_hardware
    from simlunar.render.transient import TransientOptions, flash_frame

    hw = LidarHardware(pulse_energy_j=1e-3)
    opts = with_hardware(FlashOptions(transient=TransientOptions(spp=64)), hw)
    cam = _camera(16, 30.0)
    bins = TimeBins.for_ranges(45.0, 60.0, 0.05)
    frame = flash_frame(_plane(), cam, bins=bins, options=opts.transient)
    omega = receiver_solid_angles(cam)
    det = opts.photon_detector(field_sr=1.0, lit_sr=omega.sum())
    got = frame.steady * omega * det.signal_photons
    d = cam.directions_device(cam.pixel_centers().reshape(-1, 2)).reshape(16, 16, 3)
    cos = d[..., 2] / np.linalg.norm(d, axis=-1)
    want = hw.lambert_signal_photons(H / cos, 0.2, np.arccos(cos), lit_sr=omega.sum(),
                                     pixel_sr=omega)  # fmt: skip
    assert got == pytest.approx(want, rel=0.02)
    assert want[8, 8] / want[0, 0] > 1.3  # centre vs corner: cos^3 x cos x cos^2 (R^2)


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
    from simlunar.render.lidar_scan import SteeredBeamOptions, beam_capture, steered_beam_scan

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
    from simlunar.render.lidar_scan import guide_directions

    d = guide_directions(cam, rc)
    scan = steered_beam_scan(cap, d, options=opts, rng=0, boresight=cam.pose)
    assert scan.valid.all()
    assert scan.points[:, 2] == pytest.approx(0.0, abs=0.025)  # 4.5 mm CRLB at 200 photons
    if altimeter:  # 50 m in windows of 4 m stepped by 2 m from 0.1 m: found in step 24-26
        p = opts.steering.pulses_per_point
        assert (4 + 24) * p <= scan.frames <= (4 + 26) * p


def test_a_return_outside_the_gate_is_lost(mi, monkeypatch):
    from simlunar.lidar.gate import GateOptions
    from simlunar.render.lidar_scan import FlashOptions, flash_scan
    from simlunar.render.transient import TransientOptions

    cam = _camera(8, 10.0)
    base = FlashOptions(detector=DET, transient=TransientOptions(spp=8), margin_m=1.0)
    monkeypatch.setattr(Terrain, "points", lambda *a, **k: pytest.fail("truth read"))
    good = flash_scan(_plane(), cam, options=base, rng=0)
    assert good.valid.all()
    # the navigation datum 5 m above the ground: the window (45 - 1 ... 45.1 + 1 m) misses it
    off = FlashOptions(detector=DET, transient=TransientOptions(spp=8), margin_m=1.0,
                       gate=GateOptions(datum_z_m=5.0))  # fmt: skip
    assert not flash_scan(_plane(), cam, options=off, rng=0).valid.any()


def test_a_descending_platform_s_cloud_lands_on_the_terrain(mi):
    # a tilted plane (z = 0.3 x) scanned while descending at 4 m/s and drifting 1 m/s east: the
    # scan takes about 2 s (slow gimbal), the platform falls about 8 m. With each beam leaving
    # from the platform's position at its firing time (the pose known exactly) every point
    # lies on the plane; the same ranges placed from the starting pose miss it by metres.
    from simlunar.lidar.trajectory import Trajectory
    from simlunar.render.lidar_scan import (
        SteeredBeamOptions,
        beam_capture,
        guide_directions,
        steered_beam_scan,
    )

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


@pytest.mark.parametrize("correct", [True, False])
def test_spad_scan_pile_up_and_its_correction(mi, correct):
    # 30 signal photons per pulse on a SPAD with a 1.5 ns dead time: the raw reading is early
    # (the first photon arrives on the pulse's leading edge); the scans' refit removes it
    from simlunar.lidar import RangeOptions
    from simlunar.render.lidar_scan import SteeredBeamOptions, beam_capture, steered_beam_scan

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
