"""Mechanics of a steered beam: two-axis pointing, move times, dwell, scan time.

Three steering models (``SteeringOptions.model``):

- ``"gimbal"`` (stop and stare): each axis moves with a trapezoidal velocity profile (rest to
  rest: accelerate at ``max_accel``, cruise at ``max_rate``, decelerate), both axes at once, so
  a move takes the longer of the two axes' times, then ``settle_s``. At each point the beam
  stays for ``pulses_per_point`` pulses at ``pulse_rate_hz``. A scan's time is the sum of its
  moves, settles and dwells. Axis move time for an angle ``d``: ``2 sqrt(d / a)`` when
  ``d <= v^2 / a`` (the axis never reaches ``v``), else ``d / v + v / a``.
- ``"galvanometer"`` (stop and stare, inertia-free mirrors): a move takes ``d / v`` plus the
  small-step response ``settle_s`` (a galvanometer is specified by its small-step response
  time and its largest angular speed; the acceleration phase is inside the step response).
- ``"continuous_raster"``: the fast axis sweeps lines of constant elevation at ``max_rate``
  over the plan's azimuth span, serpentine, and fires each point as the beam passes it (no
  stop); elevations are grouped into lines of ``line_pitch_rad`` (the slow axis fine-steers
  within a line, an assumption), only lines holding points are swept, a line with points
  closer than the beam's travel during one dwell (``max_rate x dwell``) is swept again for
  them, and a turnaround (``2 v / a``) or the slow axis's step to the next line (trapezoid +
  settle), whichever is longer, separates sweeps. Its time depends on the lines a plan
  occupies, not on how many points each holds: a grid is its cheapest pattern.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.registry import Options, option

#: the steering models of :class:`SteeringOptions`
MODELS = ("gimbal", "galvanometer", "continuous_raster")


@dataclass(frozen=True)
class SteeringOptions(Options):
    """Two-axis steering mechanics (both axes alike)."""

    # lower bounds keep every modelled scan time finite (a rate of 1e-300 made it infinite)
    max_rate_rad_s: float = option(
        2.0, doc="largest angular speed of an axis (at least 1e-6)", unit="rad/s", ge=1e-6
    )
    max_accel_rad_s2: float = option(
        50.0, doc="largest angular acceleration of an axis (at least 1e-6)", unit="rad/s^2",
        ge=1e-6,
    )  # fmt: skip
    settle_s: float = option(
        1e-3, doc="settling time after every move (at most 1000 s)", unit="s", key_unit="ms",
        ge=0, le=1000.0,
    )  # fmt: skip
    pulse_rate_hz: float = option(
        10_000.0, doc="laser pulse repetition rate (1e-3 .. 1e9)", unit="1/s", ge=1e-3, le=1e9
    )
    pulses_per_point: int = option(
        1, doc="pulses accumulated into one point's histogram (at most 1e6)", ge=1, le=1_000_000
    )
    model: str = option("gimbal", doc="the steering model (module docstring)", choices=MODELS)
    line_pitch_rad: float | None = option(
        None,
        doc="continuous raster: elevation height of a line; required by that model (the "
        "steered-beam sensor sets it to the guide camera's pixel pitch when None)",
        unit="rad",
        key_unit="mrad",
        gt=0,
    )

    @property
    def move_accel_rad_s2(self) -> float:
        """The acceleration of a stop-and-stare move: infinite for a galvanometer (its
        acceleration is inside the small-step response ``settle_s``)."""
        return np.inf if self.model == "galvanometer" else float(self.max_accel_rad_s2)

    @property
    def dwell_s(self) -> float:
        """Time spent firing at one point (s)."""
        return int(self.pulses_per_point) / self.pulse_rate_hz


@dataclass(frozen=True)
class ScanTiming:
    """Time budget of one ordered scan (s).

    Attributes
    ----------
    total_s : float
        ``move_s + settle_s + dwell_s``.
    move_s, settle_s, dwell_s : float
        Sums over the scan of the axis moves, the settles and the dwells.
    """

    total_s: float
    move_s: float
    settle_s: float
    dwell_s: float


def axis_move_time(delta, options: SteeringOptions) -> np.ndarray:
    """Rest-to-rest time (s) of one axis turning by ``delta`` (rad, any sign, array)."""
    d = np.abs(np.asarray(delta, float))
    v, a = options.max_rate_rad_s, options.max_accel_rad_s2
    if options.model == "galvanometer":
        return d / v
    return np.where(d <= v * v / a, 2.0 * np.sqrt(d / a), d / v + v / a)


def move_time(a: np.ndarray, b: np.ndarray, options: SteeringOptions) -> np.ndarray:
    """Time (s) of the moves from pointings ``a`` to ``b`` ((..., 2) rad), settle included.

    Both axes move at once; a zero move costs nothing (no settle).
    """
    d = np.max(np.abs(np.asarray(b, float) - np.asarray(a, float)), axis=-1)
    t = axis_move_time(d, options)
    return np.where(d > 0, t + options.settle_s, 0.0)


def scan_timing(
    angles: np.ndarray, order=None, *, options: SteeringOptions, start=None
) -> ScanTiming:
    """Time of a scan visiting ``angles[order]`` in turn.

    Parameters
    ----------
    angles : (n, 2) float
        Pointing angles (azimuth, elevation) of the points (rad).
    order : (n,) int or None
        Visiting order (a permutation); None = as given.
    options : SteeringOptions
    start : (2,) float or None
        Pointing before the scan (rad); None = the first point (no initial move).

    Returns
    -------
    ScanTiming
    """
    p = _angle_array(angles)
    if options.model == "continuous_raster":
        return raster_sweep(p, options=options).timing
    if order is not None:
        p = p[np.asarray(order)]
    if len(p) == 0:
        return ScanTiming(0.0, 0.0, 0.0, 0.0)
    first = p[:1] if start is None else np.asarray(start, float).reshape(1, 2)
    path = np.concatenate([first, p], axis=0)
    d = np.max(np.abs(np.diff(path, axis=0)), axis=1)
    moving = d > 0
    move = float(axis_move_time(d[moving], options).sum())
    settle = float(moving.sum() * options.settle_s)
    dwell = float(len(p) * options.dwell_s)
    return ScanTiming(total_s=move + settle + dwell, move_s=move, settle_s=settle, dwell_s=dwell)


def _angle_array(angles) -> np.ndarray:
    """``angles`` as an (n, 2) float64 array of (azimuth, elevation) (rad); a clear error
    for any other shape."""
    p = np.asarray(angles, float)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"angles must have shape (n, 2), got {p.shape}")
    return p


def pointing_angles(directions: np.ndarray, boresight_pose) -> np.ndarray:
    """Gimbal angles (azimuth, elevation) (n, 2) rad of unit world ``directions`` (n, 3).

    The gimbal's zero is ``boresight_pose``'s forward axis (device +z, OpenCV style):
    azimuth turns about device -y (towards device +x), elevation towards device -y (up in
    the image). Angles are exact (not small-angle): az = atan2(x, z), el = atan2(-y, hypot(x, z)).
    """
    d = np.asarray(directions, float) @ np.asarray(boresight_pose.rotation, float)
    az = np.arctan2(d[:, 0], d[:, 2])
    el = np.arctan2(-d[:, 1], np.hypot(d[:, 0], d[:, 2]))
    return np.stack([az, el], axis=1)


def point_times(
    angles: np.ndarray, order=None, *, options: SteeringOptions, start=None
) -> np.ndarray:
    """When each pointing's first pulse fires (s from the scan's start), in the input order.

    The beam moves to the k-th pointing of ``order`` (move + settle, nothing for a zero move),
    fires its ``pulses_per_point`` pulses (the dwell) and moves on; so the last point's time
    plus one dwell is :func:`scan_timing`'s ``total_s``.

    Parameters
    ----------
    angles : (n, 2) float
        Gimbal angles (rad).
    order : (n,) int or None
        Visiting order (None: as given).
    options : SteeringOptions
    start : (2,) float or None
        Pointing before the scan (None: the first point).

    Returns
    -------
    (n,) float64
    """
    p = np.asarray(angles, float)
    n = len(p)
    if options.model == "continuous_raster":
        return raster_sweep(p, options=options).times
    idx = np.arange(n) if order is None else np.asarray(order)
    if n == 0:
        return np.zeros(0)
    q = p[idx]
    first = q[:1] if start is None else np.asarray(start, float).reshape(1, 2)
    d = np.max(np.abs(np.diff(np.concatenate([first, q], axis=0), axis=0)), axis=1)
    move = np.where(d > 0, axis_move_time(d, options) + options.settle_s, 0.0)
    fire = np.cumsum(move) + np.arange(n) * options.dwell_s
    out = np.empty(n)
    out[idx] = fire
    return out


@dataclass(frozen=True, eq=False)
class RasterSweep:
    """A continuous raster's schedule of a plan (:func:`raster_sweep`).

    Attributes
    ----------
    times : (n,) float64
        When each point fires (s from the scan's start), in the input order.
    order : (n,) int64
        Firing order (a permutation).
    sweeps : int
        Line sweeps (a line swept again for points too close to fire in one pass counts twice).
    lines : int
        Distinct lines holding points.
    timing : ScanTiming
        ``move_s``: the sweeps; ``settle_s``: turnarounds and line steps; ``dwell_s``: the
        last point's dwell past the end of the last sweep (0 if it fits inside).
    """

    times: np.ndarray
    order: np.ndarray
    sweeps: int
    lines: int
    timing: ScanTiming


def raster_sweep(angles: np.ndarray, *, options: SteeringOptions) -> RasterSweep:
    """Schedule a plan's pointings on a continuous raster (module docstring).

    Parameters
    ----------
    angles : (n, 2) float
        Pointing angles (azimuth, elevation) (rad); the visiting order is the raster's own.
    options : SteeringOptions
        ``max_rate_rad_s`` (sweep speed), ``max_accel_rad_s2`` (turnaround ``2 v / a``, and
        the slow axis's trapezoid), ``settle_s`` (after a line step), ``line_pitch_rad``,
        ``dwell_s``.

    Returns
    -------
    RasterSweep
    """
    p = _angle_array(angles)
    if options.line_pitch_rad is None:
        raise ValueError("a continuous raster needs line_pitch_rad (the height of a line)")
    n = len(p)
    if n == 0:
        return RasterSweep(np.zeros(0), np.zeros(0, np.int64), 0, 0, ScanTiming(0.0, 0, 0, 0))
    v, a, dwell = options.max_rate_rad_s, options.max_accel_rad_s2, options.dwell_s
    az0, span = p[:, 0].min(), float(np.ptp(p[:, 0]))
    sweep_s, turn_s = span / v, 2.0 * v / a
    line = np.floor((p[:, 1].max() - p[:, 1]) / options.line_pitch_rad + 0.5).astype(np.int64)
    gap = v * dwell  # the beam's travel while one point fires
    # passes: points of a line in azimuth, first-fit into passes whose last point is >= gap back
    srt = np.lexsort((p[:, 0], line))
    pass_of = np.zeros(n, np.int64)
    key = []
    start = 0
    for i in range(1, n + 1):
        if i == n or line[srt[i]] != line[srt[start]]:
            ends: list[float] = []
            for j in srt[start:i]:
                for q, e in enumerate(ends):
                    if p[j, 0] >= e + gap - 1e-15:
                        ends[q], pass_of[j] = p[j, 0], q
                        break
                else:
                    pass_of[j] = len(ends)
                    ends.append(p[j, 0])
            key += [(int(line[srt[start]]), q) for q in range(len(ends))]
            start = i
    times = np.empty(n)
    t, move, settle, forward, prev_line = 0.0, 0.0, 0.0, True, None
    sweep_id = {k: s for s, k in enumerate(key)}
    sid = np.array([sweep_id[(int(line[j]), int(pass_of[j]))] for j in range(n)])
    for s_i, (ln, _) in enumerate(key):
        if prev_line is not None:
            step = turn_s
            if ln != prev_line:
                d = (ln - prev_line) * options.line_pitch_rad
                step = max(turn_s, float(axis_move_time(d, options)) + options.settle_s)
            t += step
            settle += step
        sel = sid == s_i
        off = (p[sel, 0] - az0) if forward else (az0 + span - p[sel, 0])
        times[sel] = t + off / v
        t += sweep_s
        move += sweep_s
        forward, prev_line = not forward, ln
    tail = max(0.0, float(times.max()) + dwell - t)
    order = np.argsort(times, kind="stable").astype(np.int64)
    timing = ScanTiming(total_s=t + tail, move_s=move, settle_s=settle, dwell_s=tail)
    return RasterSweep(times, order, len(key), len(set(line.tolist())), timing)


__all__ = [
    "MODELS",
    "RasterSweep",
    "ScanTiming",
    "SteeringOptions",
    "axis_move_time",
    "move_time",
    "point_times",
    "pointing_angles",
    "raster_sweep",
    "scan_timing",
]
