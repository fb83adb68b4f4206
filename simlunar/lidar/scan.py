"""Steered-beam LIDAR acquisition: a gimbal / galvanometer beam visits planned directions.

:func:`steered_beam_scan` orders the planned directions (:func:`simlunar.lidar.order_scan`),
times them on the steering mechanics (:mod:`simlunar.lidar.steering`), predicts each beam's
range from the gate's reference plane (:mod:`simlunar.lidar.gate`; an altimeter reading with
:func:`altimeter_datum`), has the returns rendered by a beam capture, applies the sensor physics
(pulse and jitter, photon counts with the sun's background and its shot noise, dead time, range
extraction: :mod:`simlunar.lidar.returns`) and prices the acquisition in seconds.

The capture is any object with the methods of :class:`simlunar.render.beam_capture.BeamCapture`
(``render_beams``, ``render_batch``, ``render_sun``, ``has_sun``, ``origin``, ``oversample``,
``sun_irradiance``), made by :func:`simlunar.render.beam_capture.beam_capture`: this package
never imports :mod:`simlunar.render` (only it imports Mitsuba). The flash LIDARs are in
:mod:`simlunar.lidar.flash` and :mod:`simlunar.render.flash_lidar`.

Ranges are slant ranges from the sensor's origin along the beam (m).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Camera, Pose
from simlunar.lidar.detector import DetectorOptions
from simlunar.lidar.flash import FlashOptions
from simlunar.lidar.footprint import FootprintOptions, spot_in_field
from simlunar.lidar.gate import GateOptions, plane_ranges, prior_ranges, read_datum
from simlunar.lidar.hardware import LidarHardware
from simlunar.lidar.ordering import OrderOptions, order_scan
from simlunar.lidar.ranging import extract_ranges
from simlunar.lidar.returns import (
    LidarScan,
    ReturnOptions,
    detect_counts,
    fired_energy_j,
    read_ranges,
)
from simlunar.lidar.steering import SteeringOptions, point_times, pointing_angles, scan_timing
from simlunar.lidar.trajectory import (
    Flight,
    PlatformMotion,
    check_airborne,
    place_points,
    rotate_small,
)
from simlunar.lidar.waveform import PulseOptions, TimeBins
from simlunar.registry import Options, option

__all__ = [
    "ALTIMETER_FIRES",
    "HARDWARE_SETS",
    "SteeredBeamOptions",
    "altimeter_datum",
    "generic_hardware",
    "guide_directions",
    "steered_beam_scan",
    "visiting_order",
    "with_hardware",
]


@dataclass(frozen=True)
class SteeredBeamOptions(ReturnOptions):
    """A steered-beam LIDAR (gimbaled altimeter or galvanometer scanner).

    The fields of every LIDAR are :class:`~simlunar.lidar.returns.ReturnOptions`'s; the
    detector's ``pulses`` is replaced by ``steering.pulses_per_point``.
    """

    footprint: FootprintOptions = option(
        doc="divergence (rad), profile and rays per beam", default_factory=FootprintOptions
    )
    steering: SteeringOptions = option(
        doc="slew rate (rad/s), acceleration (rad/s^2), settle (s), pulse rate (Hz), "
        "pulses per point",
        default_factory=SteeringOptions,
    )
    order: OrderOptions = option(
        doc="how the points are ordered (simlunar.lidar.ordering)", default_factory=OrderOptions
    )
    window_m: float = option(
        8.0, doc="range window of each rendered batch (> 2 margin_m)", unit="m", gt=0
    )
    field_clip: bool = option(
        False,
        doc="scale each beam's signal by the share of its spot inside the receiver's field "
        "(the hardware's field_rad; simlunar.lidar.footprint.spot_in_field: 0.865 for a "
        "Gaussian beam as wide as the field); False: the receiver sees the whole spot (ideal)",
    )
    batch: int = option(4096, doc="beams per render launch (memory only; at most 1e6)", ge=1,
                        le=1_000_000)  # fmt: skip
    motion: PlatformMotion | None = option(
        None,
        doc="the platform's motion during the scan (simlunar.lidar.trajectory); None = at rest. "
        "Used by simlunar.sensors.SteeredBeam (which starts it at the guide camera); "
        "steered_beam_scan takes the trajectory itself",
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.window_m > 2 * self.margin_m:
            raise ValueError(
                f"window_m must be > 2 margin_m, got {self.window_m} <= 2 x {self.margin_m}"
            )

    @property
    def window(self) -> TimeBins:
        """Bins of one batch's window (start set per batch)."""
        return TimeBins.for_ranges(0.0, self.window_m, self.bin_range_m)


#: what an instrument's hardware sets in the options it measures with: a
#: :class:`~simlunar.lidar.hardware.LidarHardware` field -> the (options class, field) pairs it
#: replaces wherever they are in the options (:func:`with_hardware` applies them; the
#: configuration refuses a second value of each)
HARDWARE_SETS: dict[str, tuple[tuple[type, str], ...]] = {
    "pulse_fwhm_s": ((PulseOptions, "fwhm_s"),),
    "jitter_s": ((PulseOptions, "jitter_s"),),
    "divergence_rad": ((FootprintOptions, "divergence_rad"),),
    "pulse_rate_hz": ((SteeringOptions, "pulse_rate_hz"), (FlashOptions, "pulse_rate_hz")),
}


def _set_from(obj, values: dict[tuple[type, str], object]):
    """``obj`` with every (class, field) of ``values`` replaced, in it and in the options
    nested in it (the hardware itself left alone)."""
    changes = {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if isinstance(v, Options) and not isinstance(v, LidarHardware):
            new = _set_from(v, values)
            if new is not v:
                changes[f.name] = new
    for (cls, name), value in values.items():
        if isinstance(obj, cls):
            changes[name] = value
    return dataclasses.replace(obj, **changes) if changes else obj


def with_hardware(options, hardware: LidarHardware):
    """``options`` (:class:`SteeredBeamOptions` or :class:`~simlunar.lidar.flash.FlashOptions`)
    measuring with ``hardware``: its photon scales
    (:meth:`~simlunar.lidar.returns.ReturnOptions.photon_detector`) and every option of
    :data:`HARDWARE_SETS` (pulse and jitter, pulse rate and, for a steered beam, its
    divergence)."""
    values = {t: getattr(hardware, k) for k, targets in HARDWARE_SETS.items() for t in targets}
    return _set_from(dataclasses.replace(options, hardware=hardware), values)


def generic_hardware(options) -> LidarHardware:
    """The hardware of ``options`` without an instrument: :class:`LidarHardware`'s defaults
    with the fields of :data:`HARDWARE_SETS` read from ``options`` (the first place each is
    found; a flash has no footprint and keeps the default divergence) and a receiver field
    equal to the beam's divergence (the receiver sees what the beam lights)."""
    found: dict[str, object] = {}

    def visit(obj) -> None:
        for k, targets in HARDWARE_SETS.items():
            for cls, name in targets:
                if isinstance(obj, cls) and k not in found:
                    found[k] = getattr(obj, name)
        for f in dataclasses.fields(obj):
            v = getattr(obj, f.name)
            if isinstance(v, Options) and not isinstance(v, LidarHardware):
                visit(v)

    visit(options)
    divergence = found.get("divergence_rad", LidarHardware().divergence_rad)
    return LidarHardware(**found, field_rad=divergence)


def guide_directions(camera: Camera, rc: np.ndarray) -> np.ndarray:
    """Unit world directions (k, 3) through the centres of guide pixels ``rc`` (k, 2) (row, col)."""
    rc = np.asarray(rc, float).reshape(-1, 2)
    return camera.rays(rc[:, ::-1] + 0.5)[1]


#: fires of one altimeter window at most: a detection is kept when a second fire of the window
#: detects a return within ``margin_m`` of it (a background avalanche does not come back)
ALTIMETER_FIRES = 3


def altimeter_datum(capture, boresight, *, options: SteeredBeamOptions, rng=None, origin=None):
    """Range the boresight and return the plane it meets: ``(datum_z (m), window steps)``.

    The beam's window (``options.window_m``) is stepped out from ``gate.min_range_m`` in
    steps of ``window_m - 2 margin_m`` (overlapping by the margins) until a return is
    detected and confirmed, up to ``gate.max_range_m``; each step fires
    ``steering.pulses_per_point`` pulses. A detection is confirmed by firing the same window
    again (at most :data:`ALTIMETER_FIRES` fires in all): two detections within ``margin_m``
    of each other lock the altimeter on the first; a window whose first fire detects nothing,
    or whose detections never agree, is passed (a single background avalanche in an empty
    window, which the first design locked onto, putting the gate tens of metres off). The
    plane is horizontal through the measured point (the IMU gives the vertical).

    Parameters
    ----------
    capture : BeamCapture
        From :func:`simlunar.render.beam_capture.beam_capture`.
    boresight : (3,) float
        Direction of the altimeter's beam (world; normalised here).
    options : SteeredBeamOptions
    rng : seed or Generator
        Photon noise.
    origin : (3,) float or None
        Where the altimeter fires from (m; a moving platform at a later round's start,
        rendered through ``capture.render_beams`` with that origin); None = the capture's origin.

    Returns
    -------
    datum_z : float
    steps : int
        Fires of the window in all (each ``pulses_per_point`` pulses before the scan).

    Raises
    ------
    NothingMeasured-like ValueError
        No return within the instrument's range.
    """
    d = np.asarray(boresight, float).reshape(1, 3)
    d = d / np.linalg.norm(d)
    det = _beam_detector(capture, options)
    bins, g = options.window, options.gate
    step = options.window_m - 2.0 * options.margin_m
    z0 = capture.origin[2] if origin is None else float(np.asarray(origin, float).reshape(3)[2])
    r0, k = g.min_range_m, 0
    while r0 < g.max_range_m:
        seen: list[float] = []
        for _ in range(ALTIMETER_FIRES):
            k += 1
            hist, bg, start = _altimeter_window(capture, d, r0, origin, options, seed=k)
            counts = detect_counts(hist, bg, bins, options.pulse, det, rng, capture.oversample)
            res = extract_ranges(counts, bins, pulse=options.pulse, options=options.ranging,
                                 apd=det.apd, pulses=det.pulses)  # fmt: skip
            if not res.valid[0]:
                if not seen:
                    break  # nothing in this window
                continue
            r = float(res.range[0]) + start
            agree = [x for x in seen if abs(x - r) <= options.margin_m]
            if agree:
                return float(z0 + agree[0] * d[0, 2]), k
            seen.append(r)
        r0 += step
    raise ValueError(f"altimeter: no return along the boresight within {g.max_range_m} m")


def _altimeter_window(capture, d, r0: float, origin, options: SteeredBeamOptions, *, seed: int):
    """The altimeter's ``seed``-th step: its histogram (1, bins * oversample), sun background
    and window start (m) for the window from ``r0`` m along ``d`` (1, 3), from the capture's
    origin or from ``origin`` (3,) m (the render's laser moved there and back)."""
    s = options.transient.seed + 7919 * seed
    if origin is None:
        hist, _ = capture.render_batch(d, 2.0 * r0, seed=s)
        return hist, (capture.render_sun(d) if capture.has_sun else 0.0), r0
    m = options.margin_m  # a window that starts at r0: the prediction a margin past it
    ret = capture.render_beams(d, np.array([r0 + m]), margin_m=m, seed=s,
                               origins=np.asarray(origin, float).reshape(1, 3))  # fmt: skip
    start = float(ret.start_opl[0]) / 2.0
    if ret.opl_offset is not None:
        start -= float(ret.opl_offset[0]) / 2.0  # the render's laser offset (0 for one beam)
    return ret.histograms, (0.0 if ret.sun is None else ret.sun), start


def visiting_order(directions: np.ndarray, *, boresight: Pose, options: SteeredBeamOptions):
    """Gimbal angles (n, 2) rad and visiting order (n,) of a scan of unit world
    ``directions`` (n, 3) from a gimbal whose zero is ``boresight``: what
    :func:`steered_beam_scan` visits, available before the scan (a multi-round acquisition
    on a moving platform starts a round after re-pointing to its first beam)."""
    angles = pointing_angles(_unit(np.asarray(directions, float)), boresight)
    return angles, order_scan(angles, steering=options.steering, options=options.order)


def steered_beam_scan(
    capture,
    directions: np.ndarray,
    *,
    options: SteeredBeamOptions,
    rng=None,
    boresight: Pose | None = None,
    flight: Flight | None = None,
) -> LidarScan:
    """Scan planned directions with a steered beam.

    Parameters
    ----------
    capture : BeamCapture
        From :func:`simlunar.render.beam_capture.beam_capture` (terrain, origin, sun, BSDF).
    directions : (n, 3) float
        Unit world directions of the planned samples, in the planner's order.
    options : SteeredBeamOptions
    rng : seed or Generator
        Photon noise.
    boresight : Pose or None
        Gimbal zero (its forward axis); None = looking along the mean direction.
    flight : Flight or None
        The platform's motion (:class:`~simlunar.lidar.trajectory.Flight`): each beam leaves
        from the trajectory's position at its firing time (``flight.start_s`` + its time in
        the scan), turned by the attitude jitter then, aimed as ``flight.retarget`` says; its
        points are placed by ``flight.navigation``; the altimeter ranges from the position at
        ``flight.start_s``. The firing times come from the pointing angles seen from the
        scan's start. None = at rest at the capture's origin.

    Returns
    -------
    LidarScan
    """
    trajectory = None if flight is None else flight.trajectory
    start_s = 0.0 if flight is None else float(flight.start_s)
    rng = np.random.default_rng(rng)
    d = _unit(np.asarray(directions, float))
    det = _beam_detector(capture, options)
    if det.apd is not None and det.apd.agc_target is not None:
        raise ValueError("apd.agc_target: a steered beam has no gain control (a flash has)")
    datum, steps = options.gate.datum_z_m, 0
    if not options.gate.altimeter:
        datum = read_datum(options.gate, rng)  # the datum itself unless it has an error
    else:
        bore = d.mean(axis=0) if boresight is None else boresight.forward
        # at t = 0 the platform is at the capture's origin
        at = None if start_s == 0 else trajectory.at(start_s)
        datum, steps = altimeter_datum(capture, bore, options=options, rng=rng, origin=at)
    if boresight is None:
        boresight = Pose.look_at(capture.origin, capture.origin + d.mean(axis=0))
    angles, order = visiting_order(directions, boresight=boresight, options=options)
    timing = scan_timing(angles, order, options=options.steering)
    lead = steps * det.pulses / options.steering.pulse_rate_hz  # the altimeter's steps first
    times = lead + point_times(angles, order, options=options.steering)
    clock = times + start_s  # when each beam fires on the trajectory
    retarget = flight is not None and flight.retarget
    if trajectory is not None:
        check_airborne(trajectory, clock, datum, options.gate.min_range_m, what="steered-beam scan")
    origins, d, fired = _aim(capture.origin, d, clock, trajectory, datum, options.gate, retarget)
    pred, margin = _predict(capture.origin if origins is None else origins, d, datum,
                            boresight.forward, options)  # fmt: skip
    ret = _render_returns(capture, fired, pred, clock, origins, options, margin)
    ranges, valid, res = _read_returns(ret, det, options, rng)
    if trajectory is None:
        points = capture.origin + ranges[:, None] * d
    else:
        points = place_points(ranges, d, clock, trajectory, flight.navigation, rng=rng)
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
        energy_j=fired_energy_j(options, (len(d) + steps) * int(options.steering.pulses_per_point)),
    )


def _unit(d: np.ndarray) -> np.ndarray:
    """Rows of ``d`` (n, 3) scaled to unit length."""
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _beam_detector(capture, options: SteeredBeamOptions) -> DetectorOptions:
    """The detector of one pointing: ``steering.pulses_per_point`` pulses, photon scales of the
    instrument under the capture's sun (the signal clipped by the receiver's field with
    ``field_clip``)."""
    det = options.photon_detector(
        pulses=options.steering.pulses_per_point, sun_irradiance=capture.sun_irradiance
    )
    if options.field_clip and options.hardware is not None:
        share = spot_in_field(options.hardware.field_rad, options.footprint)
        det = dataclasses.replace(det, signal_photons=det.signal_photons * share)
    return det


def _aim(origin, d, times, trajectory, datum_z, gate: GateOptions, retarget: bool):
    """Where the beams leave from and where they point, at their firing ``times`` (n,) s.

    Returns
    -------
    origins : (n, 3) float or None
        The platform's positions (m); None without a ``trajectory`` (at rest at ``origin``).
    commanded : (n, 3) float
        The directions the sensor commands (retargeted to the reference plane if asked).
    fired : (n, 3) float
        The directions the beams take: ``commanded`` turned by the line of sight's attitude
        jitter, which the sensor ignores.
    """
    if trajectory is None:
        return None, d, d
    origins = trajectory.at(times)
    if retarget:
        d = _retarget(origin, d, origins, datum_z, gate)
    return origins, d, rotate_small(d, trajectory.attitude_at(times))


def _read_returns(ret, det: DetectorOptions, options: SteeredBeamOptions, rng):
    """Slant ranges (n,) m (NaN where invalid), their validity (n,) and the RangeResult of
    rendered :class:`~simlunar.render.beam_capture.BeamReturns` ``ret``."""
    bins = options.window
    bg = 0.0 if ret.sun is None else ret.sun
    counts = detect_counts(ret.histograms, bg, bins, options.pulse, det, rng, ret.oversample)
    res = read_ranges(counts, bg, bins, options.pulse, det, options.ranging)
    valid = res.valid & np.isfinite(ret.start_opl)
    ranges = res.range + ret.start_opl / 2.0
    if ret.opl_offset is not None:
        ranges = ranges - ret.opl_offset / 2.0  # the render's laser offset, not the sensor's
    return np.where(valid, ranges, np.nan), valid, res


def _retarget(origin, d, origins, datum_z, gate) -> np.ndarray:
    """Directions from ``origins`` (n, 3) to where the rays ``origin + r d`` meet the plane
    ``z = datum_z`` (unchanged where a ray misses it within the gate's range)."""
    r = plane_ranges(origin, d, datum_z=datum_z, options=gate)
    ok = np.isfinite(r) & (r < gate.max_range_m)
    target = origin + np.where(ok, r, 1.0)[:, None] * d
    out = target - origins
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    return np.where(ok[:, None], out, d)


def _predict(origin, d, datum: float, boresight, options: SteeredBeamOptions):
    """Each beam's predicted range (n,) and the margin (m) of its batch's window: the plane's
    range and ``margin_m``, or with the gate's prior the middle of each beam's interval
    (:func:`~simlunar.lidar.gate.prior_ranges`) and ``margin_m`` plus the largest half-width
    (a window of ``window_m`` must hold it: a ``ValueError`` names the least)."""
    g = options.gate
    if g.datum_sigma_m == 0 and g.max_slope_rad == 0:
        return plane_ranges(origin, d, datum_z=datum, options=g), options.margin_m
    lo, hi = prior_ranges(origin, d, datum_z=datum, boresight=boresight, options=g)
    half = 0.5 * (hi - lo)
    margin = options.margin_m + float(half.max())
    if not options.window_m > 2 * margin:
        raise ValueError(
            f"gate prior: window_m must exceed {2 * margin:.3g} m (2 x (margin_m + the "
            f"prior's largest half-width {half.max():.3g} m)), got {options.window_m}"
        )
    return 0.5 * (lo + hi), margin


def _render_returns(capture, d, pred, times, origins, options: SteeredBeamOptions, margin=None):
    """The beams' returns (input order), rendered in firing order when the platform moves
    between launches (``origins`` (n, 3) m at the firing ``times``; None: at rest); windows
    with ``margin`` (m; None: ``options.margin_m``) either side of the predictions."""
    margin = options.margin_m if margin is None else margin
    if origins is None:
        return capture.render_beams(d, pred, margin_m=margin,
                                    seed=options.transient.seed)  # fmt: skip
    fire = np.argsort(times, kind="stable")
    inv = np.empty_like(fire)
    inv[fire] = np.arange(len(fire))
    ret = capture.render_beams(d[fire], pred[fire], margin_m=margin,
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
