"""Flash LIDARs rendered end to end on a plane: flash scan, micromirror flash, the lidar equation
per pixel, the range gate (the reading on arrays: tests/lidar/test_flash.py)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import DetectorOptions, PulseOptions
from simlunar.terrain import Terrain
from tests.render._lidar_planes import DET, H, _camera, _plane

pytestmark = pytest.mark.render


def test_flash_scan_on_a_plane(mi):
    from simlunar.lidar.flash import FlashOptions
    from simlunar.render.flash_lidar import flash_scan
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


def test_micromirror_flash_lights_only_the_planned_pixels(mi):
    from simlunar.lidar.flash import FlashOptions
    from simlunar.render.flash_lidar import micromirror_flash
    from simlunar.render.transient import TransientOptions

    cam = _camera(32, 6.0)
    uv = np.array([[3.5, 3.5], [2.5, 2.5], [20.5, 9.5], [30.5, 30.5], [12.5, 27.5]])
    # receiver 8 x 8: the first two dots share receiver pixel (0, 0), so two frames
    # (tests/lidar/test_flash.py checks the frames themselves)
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
    from simlunar.lidar.flash import FlashOptions, receiver_solid_angles
    from simlunar.lidar.hardware import LidarHardware
    from simlunar.lidar.scan import with_hardware
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


def test_micromirror_photons_follow_the_lidar_equation_per_dot(mi):
    # a micromirror of 8 x 8 mirrors (the guide camera's pixels, 6 deg field) with a receiver of
    # the same 8 x 8 pixels: each receiver pixel sees its dot whole. A dot lit alone gets
    # E / (8 x 8) of the pulse, so its expected photons are the beam's lidar equation
    # (E / h nu) (rho / pi) cos(theta) A / R^2 eta divided by 64 (a DMD: equal shares)
    from simlunar.geometry import Projector
    from simlunar.lidar import TimeBins
    from simlunar.lidar.flash import FlashOptions, micromirror_lit_sr, receiver_solid_angles
    from simlunar.lidar.hardware import instrument
    from simlunar.lidar.scan import with_hardware
    from simlunar.render.lights import ProjectorLight
    from simlunar.render.transient import TransientOptions, flash_frame

    hw = instrument("micromirror_flash")
    opts = with_hardware(FlashOptions(transient=TransientOptions(spp=64)), hw)
    cam = _camera(8, 6.0)
    bins = TimeBins.for_ranges(45.0, 60.0, 0.05)
    for r, c in ((4, 4), (1, 6)):
        pattern = np.zeros((8, 8), np.float32)
        pattern[r, c] = 1.0
        light = ProjectorLight(Projector(cam.intrinsics, cam.pose), pattern,
                               scale=opts.transient.laser_intensity)  # fmt: skip
        frame = flash_frame(_plane(), cam, bins=bins, options=opts.transient, projector=light)
        omega = receiver_solid_angles(cam)
        det = opts.photon_detector(field_sr=1.0, lit_sr=micromirror_lit_sr(cam))
        got = frame.steady[r, c] * omega[r, c] * det.signal_photons
        d = cam.directions_device(np.array([[c + 0.5, r + 0.5]]))[0]
        cos = d[2] / np.linalg.norm(d)
        want = hw.lambert_signal_photons(H / cos, 0.2, np.arccos(cos)) / 64
        assert got == pytest.approx(want, rel=0.03)
        assert np.delete(frame.steady.ravel(), r * 8 + c).max() < 1e-3 * frame.steady[r, c]
    # about 1.9e3 photons per dot and pulse from albedo 0.12 at 50 m on a 128 x 128 array
    full = hw.lambert_signal_photons(50.0, 0.12) / 128**2
    assert 1e3 < full < 4e3


def test_a_return_outside_the_gate_is_lost(mi, monkeypatch):
    from simlunar.lidar.flash import FlashOptions
    from simlunar.lidar.gate import GateOptions
    from simlunar.render.flash_lidar import flash_scan
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


def _moving_micromirror(trajectory, navigation):
    """Six dots of a 32 x 32 guide camera (6 deg field, 50 m above the z = 0 plane) timed by an
    8 x 8 receiver: the first three share receiver pixel (0, 0), so frames 0, 1, 2 (the rest
    fire in frame 0); 4 pulses at 20 Hz = 0.2 s a frame."""
    from simlunar.lidar.flash import FlashOptions
    from simlunar.lidar.trajectory import Flight
    from simlunar.render.flash_lidar import micromirror_flash
    from simlunar.render.transient import TransientOptions

    cam = _camera(32, 6.0)
    uv = np.array([[0.5, 0.5], [2.5, 1.5], [3.5, 3.5], [20.5, 9.5], [30.5, 30.5], [12.5, 27.5]])
    det = DetectorOptions(signal_photons=2e6 * 16, background_photons_per_s=0.0, pulses=4)
    opts = FlashOptions(detector=det, pulse=PulseOptions(fwhm_s=1e-9),
                        transient=TransientOptions(spp=256), pulse_rate_hz=20.0)  # fmt: skip
    scan = micromirror_flash(_plane(), cam, uv, options=opts, receiver_shape=(8, 8), rng=0,
                             flight=Flight(trajectory, navigation))  # fmt: skip
    assert scan.frames == 3 and scan.seconds == pytest.approx(3 * 0.2)
    assert scan.times == pytest.approx([0.0, 0.2, 0.4, 0.0, 0.0, 0.0])
    assert scan.valid.all()
    return cam, uv, opts, scan


def test_a_moving_micromirror_renders_each_frame_from_its_pose(mi):
    # a 10 m/s descent with (2, -1) m/s drift and 1 mrad of jitter from (0, 0, 50): frame f
    # fires at 0.2 f s from p(t) = (2t, -t, 50 - 10t), every dot along the camera's ray of its
    # planned pixel turned by the jitter then. Ranges: where that ray from p(t) meets the
    # plane, R = z(t) / -d'_z (2 m shorter a frame); with the exact pose every point lands
    # there. Tolerance: one range bin (the at-rest dots' range error, above) along a ray
    # with |d'_z| <= 1 (and |d'_xy| < 0.06 of it across)
    from simlunar.lidar.trajectory import Navigation, Trajectory, rotate_small

    tr = Trajectory.descent((0.0, 0.0, H), 10.0, horizontal_m_s=(2.0, -1.0),
                            attitude_jitter_rad=1e-3, jitter_seed=5)  # fmt: skip
    cam, uv, opts, scan = _moving_micromirror(tr, Navigation("exact"))
    t = scan.times
    w = tr.attitude_at(t)
    assert np.abs(w).max() > 2e-4  # the jitter is there
    d = rotate_small(cam.rays(uv)[1], w)
    p = tr.at(t)
    want_r = p[:, 2] / -d[:, 2]
    assert np.abs(scan.ranges - want_r).max() < opts.bin_range_m
    assert want_r[2] < want_r[0] - 3.9  # 4 m closer two frames on
    assert np.abs(scan.points[:, 2]).max() < opts.bin_range_m
    truth = p + want_r[:, None] * d
    assert np.abs(scan.points - truth).max() < opts.bin_range_m


def test_a_descending_micromirror_placed_from_its_start_is_lifted_by_the_metres_descended(mi):
    # 10 m/s straight down, the pose at t = 0 for every dot ("start"): a dot of frame f ranges
    # R = (50 - 10 t) / -d_z along its ray and is placed at (0, 0, 50) + R d, whose height
    # is 50 - (50 - 10 t) = 10 t: 0, 2 and 4 m for frames 0, 1, 2, while its horizontal
    # place is the true one (no drift: the ray leaves from the same x, y)
    from simlunar.lidar.trajectory import Navigation, Trajectory

    tr = Trajectory.descent((0.0, 0.0, H), 10.0)
    cam, uv, opts, scan = _moving_micromirror(tr, Navigation("start"))
    lift = np.array([0.0, 2.0, 4.0, 0.0, 0.0, 0.0])
    assert scan.points[:, 2] == pytest.approx(lift, abs=opts.bin_range_m)
    d = cam.rays(uv)[1]
    truth_xy = ((H - lift) / -d[:, 2])[:, None] * d[:, :2]
    assert scan.points[:, :2] == pytest.approx(truth_xy, abs=opts.bin_range_m)


def test_pattern_frames_render_the_frame_of_a_freshly_loaded_scene(mi):
    # one scene, patterns swapped through mi.traverse (the micromirror's frames at rest), gives
    # each pattern's frame exactly as a scene loaded for it alone; the sun image is rendered
    # once and is the same
    from simlunar.geometry import Projector
    from simlunar.lidar import TimeBins
    from simlunar.render.lights import ProjectorLight, SunLight
    from simlunar.render.transient import PatternFrames, TransientOptions, flash_frame

    cam = _camera(16, 6.0)
    receiver = type(cam)(cam.intrinsics.scaled(0.5), cam.pose)
    bins = TimeBins.for_ranges(45.0, 60.0, 0.05)
    opts = TransientOptions(spp=64)
    sun = SunLight(elevation=np.radians(30.0), azimuth=np.radians(90.0), irradiance=1.0)
    a, b = np.zeros((16, 16), np.float32), np.zeros((16, 16), np.float32)
    a[2, 3] = a[9, 12] = 1.0
    b[5, 5] = b[14, 1] = 1.0

    def light(p):
        return ProjectorLight(Projector(cam.intrinsics, cam.pose), p)

    frames = PatternFrames(_plane(), receiver, bins=bins, options=opts, sun=sun, projector=light(a))
    first, second = frames.render(), frames.render(b)
    for got, pattern in ((first, a), (second, b)):
        fresh = flash_frame(_plane(), receiver, bins=bins, options=opts, sun=sun,
                            projector=light(pattern))  # fmt: skip
        np.testing.assert_array_equal(got.histograms, fresh.histograms)
        np.testing.assert_array_equal(got.sun, fresh.sun)
    # the two patterns light different receiver pixels
    assert not np.array_equal(first.steady > 0, second.steady > 0)
    assert second.sun is first.sun
