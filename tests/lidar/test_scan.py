"""Steered-beam LIDAR acquisition: on arrays through a capture that returns a plane's impulse
responses (ranges, order, time, the altimeter's steps, a moving platform's firing order), and
rendered end to end on a plane (ranges, ordering and timing, a gate that never reads the truth, a
moving platform, SPAD pile-up); flash LIDARs: test_flash.py and tests/render/test_flash_lidar.py."""

from __future__ import annotations

import dataclasses

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
from simlunar.lidar.gate import GateOptions
from simlunar.lidar.scan import SteeredBeamOptions, altimeter_datum, steered_beam_scan
from simlunar.lidar.waveform import splat_paths
from simlunar.terrain import Terrain
from tests.render._lidar_planes import DET, H, _camera, _plane


@pytest.mark.render
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


@pytest.mark.render
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


@pytest.mark.render
def test_a_descending_platform_s_cloud_lands_on_the_terrain(mi):
    # a tilted plane (z = 0.3 x) scanned while descending at 4 m/s and drifting 1 m/s east: the
    # scan takes about 2 s (slow gimbal), the platform falls about 8 m. With each beam leaving
    # from the platform's position at its firing time (the pose known exactly) every point
    # lies on the plane; the same ranges placed from the starting pose miss it by metres.
    from simlunar.lidar.scan import SteeredBeamOptions, guide_directions, steered_beam_scan
    from simlunar.lidar.trajectory import Flight, Trajectory
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
    scan = steered_beam_scan(cap, d, options=opts, rng=0, boresight=cam.pose, flight=Flight(traj))
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
        s2 = steered_beam_scan(cap, d, options=opts, rng=0, boresight=cam.pose,
                               flight=Flight(jit, nav))  # fmt: skip
        assert s2.valid.mean() > 0.9
        q = s2.points[s2.valid]
        miss = np.abs(q[:, 2] - 0.3 * q[:, 0])
        assert (miss.max() < 0.03) if on_plane else (miss.max() > 1.0)


@pytest.mark.render
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


@dataclasses.dataclass(frozen=True, eq=False)
class _Returns:
    """The fields of BeamReturns that a scan reads."""

    histograms: np.ndarray
    start_opl: np.ndarray
    sun: None
    oversample: int
    opl_offset: None


class _PlaneCapture:
    """A beam capture without rendering: each beam's return is a unit impulse at the range where
    its ray from its origin meets the plane ``z = 0`` (tent-splatted on ``oversample`` finer
    bins, as the film does), each batch's window ``margin_m`` before its predicted range."""

    has_sun, sun_irradiance, oversample = False, 1.0, 2

    def __init__(self, origin, window):
        self.origin, self.window, self.launches = np.asarray(origin, float), window, []

    def _hist(self, d, start_opl, origins):
        o = np.broadcast_to(self.origin if origins is None else origins, d.shape)
        r = o[:, 2] / -d[:, 2]
        fine = dataclasses.replace(self.window.refined(self.oversample), start_opl=0.0)
        return splat_paths(2.0 * r[:, None] - np.reshape(start_opl, (-1, 1)), 1.0, fine)

    def render_batch(self, directions, start_opl, seed=0, origins=None):
        d = np.asarray(directions, float)
        return self._hist(d, start_opl, origins).astype(np.float32), np.zeros(len(d))

    def render_beams(self, directions, predicted_range, *, margin_m, seed, origins=None):
        d = np.asarray(directions, float)
        start = 2.0 * np.maximum(predicted_range - margin_m, 0.0)
        self.launches.append(None if origins is None else np.array(origins))
        return _Returns(
            histograms=self._hist(d, start, origins).astype(np.float32),
            start_opl=start,
            sun=None,
            oversample=self.oversample,
            opl_offset=None,
        )


def _beam_options(**kwargs):
    steer = SteeringOptions(max_rate_rad_s=1.0, max_accel_rad_s2=10.0, settle_s=1e-3,
                            pulse_rate_hz=1000.0, pulses_per_point=4)  # fmt: skip
    return SteeredBeamOptions(pulse=PulseOptions(fwhm_s=1e-9), steering=steer, window_m=4.0,
                              detector=DetectorOptions(signal_photons=200.0,
                                                       background_photons_per_s=0.0),
                              margin_m=1.0, **kwargs)  # fmt: skip


def test_steered_scan_on_arrays_reads_the_plane():
    # 40 beams from 50 m over the plane z = 0, gated by the datum z = 0: every range is
    # 50 / cos within a tenth of a bin, the order a permutation priced by the steering model
    opts = _beam_options()
    cam = _camera(64, 40.0)
    d = cam.rays(np.random.default_rng(0).uniform(0, 64, (40, 2)))[1]
    cap = _PlaneCapture(cam.position, opts.window)
    scan = steered_beam_scan(cap, d, options=opts, rng=1, boresight=cam.pose)
    assert scan.valid.all()
    assert scan.ranges == pytest.approx(H / -d[:, 2], abs=0.1 * opts.bin_range_m)
    assert scan.points[:, 2] == pytest.approx(0.0, abs=0.1 * opts.bin_range_m)
    assert sorted(scan.order) == list(range(40))
    from simlunar.lidar import pointing_angles

    timing = scan_timing(pointing_angles(d, cam.pose), scan.order, options=opts.steering)
    assert scan.seconds == pytest.approx(timing.total_s)
    assert scan.frames == 40 * 4
    # each beam is measured when the beam gets there: the first visited at 0 s, in order
    assert scan.times[scan.order[0]] == 0.0
    assert np.all(np.diff(scan.times[scan.order]) > 0)


def test_the_altimeter_finds_the_plane_and_its_steps_cost_time():
    # the window (4 m, margins 1 m) steps out in 2 m steps from 0.1 m: step k covers
    # [r0, r0 + 4] m with r0 = 0.1 + 2 (k - 1), so the plane 50 m below the boresight is first
    # inside in step k = 24 (46.1 to 50.1 m), fired twice (the detection confirmed): 23 + 2 =
    # 25 fires of pulses_per_point pulses each before the scan starts
    opts = _beam_options(gate=GateOptions(altimeter=True))
    cam = _camera(64, 40.0)
    cap = _PlaneCapture(cam.position, opts.window)
    datum, steps = altimeter_datum(cap, [0.0, 0.0, -1.0], options=opts, rng=0)
    assert datum == pytest.approx(0.0, abs=0.1 * opts.bin_range_m)
    assert steps == 25
    d = cam.rays(np.random.default_rng(0).uniform(0, 64, (10, 2)))[1]
    scan = steered_beam_scan(cap, d, options=opts, rng=1, boresight=cam.pose)
    lead = 25 * 4 / 1000.0
    assert scan.seconds == pytest.approx(scan.timing.total_s + lead)
    assert scan.frames == (10 + 25) * 4
    assert scan.times.min() == pytest.approx(lead)
    # no plane within the instrument's range: a clear error
    far = _PlaneCapture([0.0, 0.0, 500.0], opts.window)
    near = _beam_options(gate=GateOptions(altimeter=True, max_range_m=100.0))
    with pytest.raises(ValueError, match=r"no return along the boresight within 100\.0 m"):
        altimeter_datum(far, [0.0, 0.0, -1.0], options=near, rng=0)


class _SpikeCapture(_PlaneCapture):
    """The plane, and in the altimeter's first fire only a return 2 m from the sensor: a
    background avalanche in an empty window (seen at the full-size landing site under the
    45 deg sun, where the first design locked onto one and gated the scan 48 m off)."""

    def render_batch(self, directions, start_opl, seed=0, origins=None):
        hist, sun = super().render_batch(directions, start_opl, seed, origins)
        if seed == self.first_seed:
            fine = dataclasses.replace(self.window.refined(self.oversample), start_opl=0.0)
            hist = hist + splat_paths(np.array([[4.0 - float(start_opl)]]), 1.0, fine)
        return hist.astype(np.float32), sun


def test_the_altimeter_passes_a_detection_that_does_not_come_back():
    # the spike is detected in window 1's first fire, not in its second and third: the window
    # is passed (3 fires), windows 2-23 are empty (22), window 24 holds the plane (2): 27
    # fires, and the datum is the plane's, not 48 m (the spike's plane)
    opts = _beam_options(gate=GateOptions(altimeter=True))
    cam = _camera(64, 40.0)
    cap = _SpikeCapture(cam.position, opts.window)
    cap.first_seed = opts.transient.seed + 7919
    datum, steps = altimeter_datum(cap, [0.0, 0.0, -1.0], options=opts, rng=0)
    assert datum == pytest.approx(0.0, abs=0.1 * opts.bin_range_m)
    assert steps == 27


def test_a_moving_platform_s_beams_are_rendered_in_firing_order():
    # a platform descending at 2 m/s: the beams leave from where it is when each fires, are
    # rendered in firing order (their origins' heights fall) and come back in the planned
    # order; with the pose known exactly every point lies on the plane
    from simlunar.lidar.trajectory import Flight, Trajectory

    opts = _beam_options()
    cam = _camera(64, 40.0)
    d = cam.rays(np.random.default_rng(0).uniform(0, 64, (30, 2)))[1]
    traj = Trajectory.descent(cam.position, 2.0)
    cap = _PlaneCapture(cam.position, opts.window)
    scan = steered_beam_scan(cap, d, options=opts, rng=1, boresight=cam.pose, flight=Flight(traj))
    fired = cap.launches[0]
    assert np.all(np.diff(fired[:, 2]) < 0)  # firing order: ever lower
    assert fired[:, 2] == pytest.approx(np.sort(H - 2.0 * scan.times)[::-1])
    assert scan.valid.all()
    assert scan.points[:, 2] == pytest.approx(0.0, abs=0.1 * opts.bin_range_m)
    # the ranges are from where the platform was: after the first beam (fired at the start),
    # shorter than from the start by more than a bin
    later = np.delete(np.arange(30), scan.order[0])
    assert np.all(scan.ranges[later] < H / -d[later, 2] - opts.bin_range_m)


def test_a_later_round_continues_the_trajectory_from_its_start_time():
    # a second round starting at t = 5 s on a 2 m/s descent from 50 m: every beam leaves from
    # 50 - 2 (5 + t) m (t its time from the round's start), the points still lie on the plane,
    # and the scan's own times and seconds are those of the same scan at rest
    from simlunar.lidar.trajectory import Flight, Trajectory

    opts = _beam_options()
    cam = _camera(64, 40.0)
    d = cam.rays(np.random.default_rng(0).uniform(0, 64, (30, 2)))[1]
    traj = Trajectory.descent(cam.position, 2.0)
    cap = _PlaneCapture(cam.position, opts.window)
    scan = steered_beam_scan(cap, d, options=opts, rng=1, boresight=cam.pose,
                             flight=Flight(traj, start_s=5.0))  # fmt: skip
    rest = steered_beam_scan(_PlaneCapture(cam.position, opts.window), d, options=opts, rng=1,
                             boresight=cam.pose)  # fmt: skip
    np.testing.assert_array_equal(scan.times, rest.times)
    assert scan.seconds == rest.seconds and scan.times.min() == 0.0
    fired = cap.launches[0]
    assert fired[:, 2] == pytest.approx(np.sort(H - 2.0 * (5.0 + scan.times))[::-1])
    assert scan.valid.all()
    assert scan.points[:, 2] == pytest.approx(0.0, abs=0.1 * opts.bin_range_m)
    # start_s = 0 is the scan that starts the trajectory, bit for bit
    a = steered_beam_scan(_PlaneCapture(cam.position, opts.window), d, options=opts, rng=1,
                          boresight=cam.pose, flight=Flight(traj))  # fmt: skip
    b = steered_beam_scan(_PlaneCapture(cam.position, opts.window), d, options=opts, rng=1,
                          boresight=cam.pose, flight=Flight(traj, start_s=0.0))  # fmt: skip
    np.testing.assert_array_equal(a.points, b.points)
    with pytest.raises(ValueError, match=r"start_s must be >= 0, got -1\.0"):
        Flight(traj, start_s=-1.0)


def test_a_later_round_s_altimeter_ranges_from_where_the_platform_is():
    # at t = 5 s of a 2 m/s descent the platform is 40 m above the plane: the altimeter's
    # window (4 m, stepped by 2 m from 0.1 m) first holds 40 m at step k = 19 (36.1 to 40.1 m),
    # not at the k = 24 of 50 m, fired twice (20 fires), and the datum is still the plane z = 0
    from simlunar.lidar.trajectory import Flight, Trajectory

    opts = _beam_options(gate=GateOptions(altimeter=True))
    cam = _camera(64, 40.0)
    cap = _PlaneCapture(cam.position, opts.window)
    datum, steps = altimeter_datum(cap, [0.0, 0.0, -1.0], options=opts, rng=0,
                                   origin=[0.0, 0.0, 40.0])  # fmt: skip
    assert datum == pytest.approx(0.0, abs=0.1 * opts.bin_range_m) and steps == 20
    d = cam.rays(np.random.default_rng(0).uniform(0, 64, (10, 2)))[1]
    traj = Trajectory.descent(cam.position, 2.0)
    scan = steered_beam_scan(cap, d, options=opts, rng=1, boresight=cam.pose,
                             flight=Flight(traj, start_s=5.0))  # fmt: skip
    assert scan.frames == (10 + 20) * 4
    assert scan.times.min() == pytest.approx(20 * 4 / 1000.0)
    # on the plane up to photon noise (these points scatter by a few mm)
    assert scan.points[:, 2] == pytest.approx(0.0, abs=0.02)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        (
            {"window_m": 4.0, "margin_m": 2.0},
            r"window_m must be > 2 margin_m, got 4\.0 <= 2 x 2\.0",
        ),
        ({"window_m": 0.0}, r"window_m must be > 0, got 0\.0"),
        ({"margin_m": -0.5}, r"margin_m must be >= 0, got -0\.5"),
        ({"bin_range_m": 0.0}, r"bin_range_m must be > 0, got 0\.0"),
        ({"batch": 0}, "batch must be >= 1, got 0"),
    ],
)
def test_steered_beam_options_refuse_bad_windows_and_batches(kw, match):
    with pytest.raises(ValueError, match=match):
        SteeredBeamOptions(**kw)
    assert SteeredBeamOptions(window_m=4.01, margin_m=2.0).window.count == 81  # just above 2 m
