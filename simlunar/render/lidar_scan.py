"""LIDAR acquisitions: steered-beam scans, flash frames and micromirror-steered flash.

Each entry point renders the returns (:mod:`simlunar.render.transient`), applies the sensor
physics of :mod:`simlunar.lidar` (pulse and jitter, photon counts with the sun's background
and its shot noise, dead time, range extraction) and prices the acquisition in seconds:

- :func:`steered_beam_scan`: a gimbal / galvanometer beam visits planned directions in the
  order of :func:`simlunar.lidar.order_scan`; time from the steering mechanics.
- :func:`~simlunar.render.flash_lidar.flash_scan`: a receiver array lit by whole-field pulses; time = pulses / rate.
- :func:`~simlunar.render.flash_lidar.micromirror_flash`: a micromirror projector co-located with the receiver lights only
  planned directions; dots that share a receiver pixel go to different frames.

Ranges are slant ranges from the sensor's origin along the beam / pixel ray (m).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from simlunar.geometry import Camera, Pose
from simlunar.lidar import (
    DetectorOptions,
    FootprintOptions,
    OrderOptions,
    PulseOptions,
    RangeOptions,
    ScanTiming,
    SteeringOptions,
    TimeBins,
    expected_counts,
    extract_ranges,
    order_scan,
    photon_counts,
    photon_counts_dead_time,
    point_times,
    pointing_angles,
    scan_timing,
    shape_waveform,
)
from simlunar.lidar.gate import GateOptions, plane_ranges
from simlunar.lidar.hardware import LidarHardware
from simlunar.lidar.spad import spad_correct
from simlunar.lidar.trajectory import Navigation, PlatformMotion, place_points, rotate_small
from simlunar.render.beam_capture import BeamCapture, capture_beams
from simlunar.render.transient import TransientOptions

__all__ = [
    "LidarScan",
    "SteeredBeamOptions",
    "altimeter_datum",
    "beam_capture",
    "guide_directions",
    "receiver_rc",
    "steered_beam_scan",
    "with_hardware",
]


@dataclass(frozen=True)
class _ReturnOptions:
    """What every LIDAR here shares: rendering the returns and reading ranges from them.

    Parameters
    ----------
    pulse : PulseOptions
        Pulse FWHM and timing jitter (s).
    detector : DetectorOptions
        Photon scales, dark counts, dead time, pulses per reading.
    ranging : RangeOptions
    transient : TransientOptions
        Rendering (path depth, seed, laser intensity W/sr).
    bin_range_m : float
        Range width of a time bin (m).
    margin_m : float
        Range margin (m) around the expected ranges.
    hardware : LidarHardware or None
        The instrument: when given, the photon scales and dark counts of ``detector`` are
        derived from it (the lidar equation, :mod:`simlunar.lidar.hardware`) and the rendered
        laser intensity and sun irradiance; ``detector``'s own ``signal_photons`` and
        ``background_photons_per_s`` are then the expert override used only without it.
        :func:`with_hardware` also sets the pulse, rates and divergence from it.
    gate : GateOptions
        The range gate: a reference plane (datum or altimeter reading) and the instrument's
        range limits (:mod:`simlunar.lidar.gate`); ``margin_m`` must cover the terrain's
        relief about the plane.
    """

    pulse: PulseOptions = field(default_factory=PulseOptions)
    detector: DetectorOptions = field(default_factory=DetectorOptions)
    ranging: RangeOptions = field(default_factory=RangeOptions)
    transient: TransientOptions = field(default_factory=TransientOptions)
    bin_range_m: float = 0.05
    margin_m: float = 2.0
    hardware: LidarHardware | None = None
    gate: GateOptions = field(default_factory=GateOptions)

    def photon_detector(
        self, *, pulses=None, field_sr=None, lit_sr=None, sun_irradiance=1.0
    ) -> DetectorOptions:
        """The detector with the photon scales of :attr:`hardware` (or the expert override).

        ``field_sr`` / ``lit_sr``: a flash pixel's solid angle and the lit field (sr); None for
        a steered beam. ``pulses`` replaces the detector's pulses per reading.
        """
        det = self.detector
        if pulses is not None:
            det = dataclasses.replace(det, pulses=int(pulses))
        if self.hardware is None:
            return det
        hw = self.hardware.detector(
            field_sr=field_sr,
            lit_sr=lit_sr,
            laser_intensity=self.transient.laser_intensity,
            sun_irradiance=max(sun_irradiance, 1e-30),
        )
        return dataclasses.replace(
            det,
            signal_photons=hw.signal_photons,
            background_photons_per_s=hw.background_photons_per_s,
            dark_count_rate_hz=hw.dark_count_rate_hz,
        )


@dataclass(frozen=True)
class SteeredBeamOptions(_ReturnOptions):
    """A steered-beam LIDAR (gimbaled altimeter or galvanometer scanner).

    Parameters
    ----------
    pulse, ranging, transient, bin_range_m
        As for every LIDAR here (:class:`_ReturnOptions`).
    detector : DetectorOptions
        Its ``pulses`` is replaced by ``steering.pulses_per_point``.
    margin_m : float
        Range margin (m) on both sides of the ray-cast ranges in each batch's window.
    footprint : FootprintOptions
        Divergence (rad), profile and rays per beam.
    steering : SteeringOptions
        Slew rate (rad/s), acceleration (rad/s^2), settle (s), pulse rate (Hz), pulses/point.
    order : OrderOptions
    window_m : float
        Range window of each rendered batch (m).
    batch : int
        Beams per render launch.
    motion : PlatformMotion or None
        The platform's motion during the scan (:mod:`simlunar.lidar.trajectory`); None = at
        rest. Used by :class:`simlunar.sensors.SteeredBeam` (which starts it at the guide
        camera); :func:`steered_beam_scan` takes the trajectory itself.
    """

    footprint: FootprintOptions = field(default_factory=FootprintOptions)
    steering: SteeringOptions = field(default_factory=SteeringOptions)
    order: OrderOptions = field(default_factory=OrderOptions)
    window_m: float = 8.0
    batch: int = 4096
    motion: PlatformMotion | None = None

    def __post_init__(self) -> None:
        if not (self.bin_range_m > 0 and self.window_m > 2 * self.margin_m >= 0):
            raise ValueError("need bin_range_m > 0 and window_m > 2 margin_m >= 0")
        if int(self.batch) < 1:
            raise ValueError(f"batch must be >= 1, got {self.batch}")

    @property
    def window(self) -> TimeBins:
        """Bins of one batch's window (start set per batch)."""
        return TimeBins.for_ranges(0.0, self.window_m, self.bin_range_m)


@dataclass(frozen=True, eq=False)
class LidarScan:
    """Ranges of one acquisition and its cost (arrays in the input order of the samples).

    Attributes
    ----------
    ranges : (n,) float64
        Slant range (m); NaN where invalid.
    valid : (n,) bool
    points : (n, 3) float64
        World points ``origin + range * direction`` (m); NaN where invalid.
    photons : (n,) float64
        Estimated signal photons of the reported return.
    order : (n,) int64
        Visiting order (indices into the samples); ``arange(n)`` for flash sensors.
    seconds : float
        Acquisition time (s).
    frames : int
        Pulses fired (steered beam) or flash frames.
    timing : ScanTiming or None
        Breakdown for steered beams.
    times : (n,) float64 or None
        When each sample was measured (s from the acquisition's start): a steered beam's
        first pulse at that pointing, a flash frame's start.
    returns : (n,) int64 or None
        Returns detected in each sample's histogram (the reported one is ``which``).
    """

    ranges: np.ndarray
    valid: np.ndarray
    points: np.ndarray
    photons: np.ndarray
    order: np.ndarray
    seconds: float
    frames: int
    timing: ScanTiming | None = None
    times: np.ndarray | None = None
    returns: np.ndarray | None = None

    def depth(self, camera: Camera) -> np.ndarray:
        """z-depth (m) of :attr:`points` along ``camera``'s optical axis (the guide view's
        depth convention of :class:`~simlunar.geometry.types.GroundTruth`); NaN where invalid."""
        return (self.points - camera.pose.position) @ camera.pose.forward


def with_hardware(options, hardware: LidarHardware):
    """``options`` (:class:`SteeredBeamOptions` or :class:`~simlunar.render.flash_lidar.FlashOptions`) measuring with
    ``hardware``: its pulse and jitter, photon scales (:meth:`_ReturnOptions.photon_detector`),
    pulse rate and, for a steered beam, its divergence."""
    out = dataclasses.replace(options, hardware=hardware, pulse=hardware.pulse)
    if isinstance(out, SteeredBeamOptions):
        return dataclasses.replace(
            out,
            footprint=dataclasses.replace(out.footprint, divergence_rad=hardware.divergence_rad),
            steering=dataclasses.replace(out.steering, pulse_rate_hz=hardware.pulse_rate_hz),
        )
    return dataclasses.replace(out, pulse_rate_hz=hardware.pulse_rate_hz)


def guide_directions(camera: Camera, rc: np.ndarray) -> np.ndarray:
    """Unit world directions (k, 3) through the centres of guide pixels ``rc`` (k, 2) (row, col)."""
    rc = np.asarray(rc, float).reshape(-1, 2)
    return camera.rays(rc[:, ::-1] + 0.5)[1]


def receiver_rc(receiver_shape, guide_shape) -> np.ndarray:
    """Receiver pixel centres as guide (row, col) index coordinates, (rows * cols, 2) float.

    A co-boresighted receiver of the same field of view: receiver pixel (i, j) has its centre at
    guide (u, v) = ((j + 1/2) W / w, (i + 1/2) H / h), i.e. index coordinates (v - 1/2, u - 1/2),
    row-major (the order of a flash scan's flattened arrays).
    """
    (h, w), (gh, gw) = receiver_shape, guide_shape
    i, j = np.mgrid[0:h, 0:w]
    v, u = (i.ravel() + 0.5) * gh / h, (j.ravel() + 0.5) * gw / w
    return np.stack([v - 0.5, u - 0.5], axis=1)


def beam_capture(terrain, origin, *, options: SteeredBeamOptions, sun=None, bsdf=None):
    """The reusable render of a steered beam at ``origin`` (3,) m over ``terrain``."""
    return BeamCapture(
        terrain,
        origin,
        footprint=options.footprint,
        window=options.window,
        options=options.transient,
        bsdf=bsdf,
        sun=sun,
        batch=options.batch,
    )


def _ranges(counts, background, bins: TimeBins, pulse, det: DetectorOptions, ranging):
    """Ranges of the counts; a SPAD's detected returns refitted without pile-up."""
    res = extract_ranges(counts, bins, pulse=pulse, options=ranging, apd=det.apd,
                         pulses=det.pulses)  # fmt: skip
    if det.regime != "spad" or not ranging.pileup_correction or not res.valid.any():
        return res
    c = np.asarray(counts).reshape(-1, bins.count)
    ok = res.valid.reshape(-1)
    bg = np.broadcast_to(np.asarray(background, float), res.valid.shape).reshape(-1)
    per_bin = (bg * det.background_photons_per_s + det.dark_count_rate_hz) * bins.bin_s
    fit = spad_correct(c[ok], bins, pulses=det.pulses, dead_time_s=det.dead_time_s,
                       sigma_bins=pulse.sigma_bins(bins), background=per_bin[ok])  # fmt: skip
    rng_m, ph = res.range.reshape(-1).copy(), res.photons.reshape(-1).copy()
    rng_m[ok], ph[ok] = fit.range, fit.photons * det.pulses
    return dataclasses.replace(res, range=rng_m.reshape(res.range.shape),
                               photons=ph.reshape(res.photons.shape))  # fmt: skip


def _counts(hist, background, bins: TimeBins, pulse, detector: DetectorOptions, rng, oversample=1):
    shaped = shape_waveform(hist, bins, pulse, oversample=oversample)
    lam = expected_counts(shaped, background, bins, detector)
    if 0 < detector.dead_time_s < np.inf:
        return photon_counts_dead_time(lam, bins, options=detector, rng=rng)
    return photon_counts(lam, options=detector, rng=rng)


def altimeter_datum(capture: BeamCapture, boresight, *, options: SteeredBeamOptions, rng=None):
    """Range the boresight and return the plane it meets: ``(datum_z (m), window steps)``.

    The beam's window (``options.window_m``) is stepped out from ``gate.min_range_m`` in
    steps of ``window_m - 2 margin_m`` (overlapping by the margins) until a return is
    detected, up to ``gate.max_range_m``; each step fires ``steering.pulses_per_point``
    pulses. The plane is horizontal through the measured point (the IMU gives the vertical).

    Raises
    ------
    NothingMeasured-like ValueError
        No return within the instrument's range.
    """
    d = np.asarray(boresight, float).reshape(1, 3)
    d = d / np.linalg.norm(d)
    det = options.photon_detector(
        pulses=options.steering.pulses_per_point, sun_irradiance=capture.sun_irradiance
    )
    bins, g = options.window, options.gate
    step = options.window_m - 2.0 * options.margin_m
    r0, k = g.min_range_m, 0
    while r0 < g.max_range_m:
        k += 1
        hist, _ = capture.render_batch(d, 2.0 * r0, seed=options.transient.seed + 7919 * k)
        bg = capture.render_sun(d) if capture.has_sun else 0.0
        counts = _counts(hist, bg, bins, options.pulse, det, rng, capture.oversample)
        res = extract_ranges(counts, bins, pulse=options.pulse, options=options.ranging,
                             apd=det.apd, pulses=det.pulses)  # fmt: skip
        if res.valid[0]:
            r = float(res.range[0]) + r0
            return float(capture.origin[2] + r * d[0, 2]), k
        r0 += step
    raise ValueError(f"altimeter: no return along the boresight within {g.max_range_m} m")


def steered_beam_scan(
    capture: BeamCapture,
    directions: np.ndarray,
    *,
    options: SteeredBeamOptions,
    rng=None,
    boresight: Pose | None = None,
    trajectory=None,
    navigation=None,
    retarget: bool = True,
) -> LidarScan:
    """Scan planned directions with a steered beam.

    Parameters
    ----------
    capture : BeamCapture
        From :func:`beam_capture` (terrain, origin, sun, BSDF).
    directions : (n, 3) float
        Unit world directions of the planned samples, in the planner's order.
    options : SteeredBeamOptions
    rng : seed or Generator
        Photon noise.
    boresight : Pose or None
        Gimbal zero (its forward axis); None = looking along the mean direction.
    trajectory : Trajectory or None
        The platform's motion (:mod:`simlunar.lidar.trajectory`): each beam leaves from its
        position at the beam's firing time, turned by the line of sight's attitude jitter;
        None = at rest at the capture's origin. The firing times come from the pointing
        angles seen from the scan's start.
    navigation : Navigation or None
        How the points are placed (:func:`simlunar.lidar.trajectory.place_points`); None =
        the pose known exactly.
    retarget : bool
        With a trajectory: command each beam from the platform's position at its firing time
        towards where its planned direction (from the start) meets the gate's reference plane
        (what navigation and the plane give, never the terrain); False: hold the planned
        directions in the world frame.

    Returns
    -------
    LidarScan
    """
    rng = np.random.default_rng(rng)
    d = np.asarray(directions, float)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    det = options.photon_detector(
        pulses=options.steering.pulses_per_point, sun_irradiance=capture.sun_irradiance
    )
    datum, steps = options.gate.datum_z_m, 0
    if options.gate.altimeter:
        bore = d.mean(axis=0) if boresight is None else boresight.forward
        datum, steps = altimeter_datum(capture, bore, options=options, rng=rng)
    if boresight is None:
        boresight = Pose.look_at(capture.origin, capture.origin + d.mean(axis=0))
    angles = pointing_angles(d, boresight)
    order = order_scan(angles, steering=options.steering, options=options.order)
    timing = scan_timing(angles, order, options=options.steering)
    lead = steps * det.pulses / options.steering.pulse_rate_hz  # the altimeter's steps first
    times = lead + point_times(angles, order, options=options.steering)
    origins, fired = None, d
    if trajectory is not None:
        origins = trajectory.at(times)
        if retarget:
            d = _retarget(capture.origin, d, origins, datum, options.gate)
        fired = rotate_small(d, trajectory.attitude_at(times))  # the jitter the sensor ignores
    pred = plane_ranges(
        capture.origin if origins is None else origins, d, datum_z=datum, options=options.gate
    )
    ret = _render_returns(capture, fired, pred, times, origins, options)
    bins = options.window
    bg = 0.0 if ret.sun is None else ret.sun
    counts = _counts(ret.histograms, bg, bins, options.pulse, det, rng, ret.oversample)
    res = _ranges(counts, bg, bins, options.pulse, det, options.ranging)
    valid = res.valid & np.isfinite(ret.start_opl)
    ranges = res.range + ret.start_opl / 2.0
    if ret.opl_offset is not None:
        ranges = ranges - ret.opl_offset / 2.0  # the render's laser offset, not the sensor's
    ranges = np.where(valid, ranges, np.nan)
    if trajectory is None:
        points = capture.origin + ranges[:, None] * d
    else:
        points = place_points(ranges, d, times, trajectory, navigation or Navigation(), rng=rng)
    return LidarScan(
        ranges=ranges,
        valid=valid,
        points=points,
        photons=res.photons,
        order=order,
        # the altimeter's window steps fire pulses_per_point pulses each before the scan
        seconds=timing.total_s + lead,
        frames=(len(d) + steps) * int(options.steering.pulses_per_point),
        timing=timing,
        times=times,
        returns=res.returns,
    )


def _retarget(origin, d, origins, datum_z, gate) -> np.ndarray:
    """Directions from ``origins`` (n, 3) to where the rays ``origin + r d`` meet the plane
    ``z = datum_z`` (unchanged where a ray misses it within the gate's range)."""
    r = plane_ranges(origin, d, datum_z=datum_z, options=gate)
    ok = np.isfinite(r) & (r < gate.max_range_m)
    target = origin + np.where(ok, r, 1.0)[:, None] * d
    out = target - origins
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    return np.where(ok[:, None], out, d)


def _render_returns(capture: BeamCapture, d, pred, times, origins, options: SteeredBeamOptions):
    """The beams' returns (input order), rendered in firing order when the platform moves
    between launches (``origins`` (n, 3) m at the firing ``times``; None: at rest)."""
    if origins is None:
        return capture_beams(capture, d, pred, margin_m=options.margin_m,
                             seed=options.transient.seed)  # fmt: skip
    fire = np.argsort(times, kind="stable")
    inv = np.empty_like(fire)
    inv[fire] = np.arange(len(fire))
    ret = capture_beams(capture, d[fire], pred[fire], margin_m=options.margin_m,
                        seed=options.transient.seed, origins=origins[fire])  # fmt: skip
    return _reorder(ret, inv)


def _reorder(ret, inv):
    """BeamReturns of beams rendered in another order, back in the input order."""
    take = {
        f.name: (getattr(ret, f.name)[inv] if isinstance(getattr(ret, f.name), np.ndarray)
                 and getattr(ret, f.name).ndim >= 1 else getattr(ret, f.name))
        for f in dataclasses.fields(ret)
    }  # fmt: skip
    return type(ret)(**take)
