"""Mechanics of a steered beam: two-axis pointing, move times, dwell, scan time.

A gimbal or galvanometer pair points the beam by two angles (azimuth, elevation). Each axis
moves with a trapezoidal velocity profile (rest to rest: accelerate at ``max_accel``, cruise
at ``max_rate``, decelerate), both axes at once, so a move takes the longer of the two axes'
times, then ``settle_s`` for the mirror or gimbal to settle. At each point the beam stays for
``pulses_per_point`` pulses at ``pulse_rate_hz`` (stop and stare). A scan's time is the sum of
its moves, settles and dwells.

Axis move time for an angle ``d``: ``2 sqrt(d / a)`` when ``d <= v^2 / a`` (the axis never
reaches ``v``), else ``d / v + v / a``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SteeringOptions:
    """Two-axis steering mechanics (both axes alike).

    Parameters
    ----------
    max_rate_rad_s : float
        Largest angular speed of an axis (rad/s).
    max_accel_rad_s2 : float
        Largest angular acceleration of an axis (rad/s^2).
    settle_s : float
        Settling time after every move (s).
    pulse_rate_hz : float
        Laser pulse repetition rate (1/s).
    pulses_per_point : int
        Pulses accumulated into one point's histogram.
    """

    max_rate_rad_s: float = 2.0
    max_accel_rad_s2: float = 50.0
    settle_s: float = 1e-3
    pulse_rate_hz: float = 10_000.0
    pulses_per_point: int = 1

    def __post_init__(self) -> None:
        for name in ("max_rate_rad_s", "max_accel_rad_s2", "pulse_rate_hz"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if not self.settle_s >= 0:
            raise ValueError(f"settle_s must be >= 0 s, got {self.settle_s}")
        if int(self.pulses_per_point) < 1:
            raise ValueError(f"pulses_per_point must be >= 1, got {self.pulses_per_point}")

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
    p = np.asarray(angles, float)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"angles must have shape (n, 2), got {p.shape}")
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


__all__ = [
    "ScanTiming",
    "SteeringOptions",
    "axis_move_time",
    "move_time",
    "point_times",
    "pointing_angles",
    "scan_timing",
]
