"""The platform's trajectory: where the sensor is when each pulse fires.

A lander hovering or descending moves while a steered beam scans (a 10 000-point scan at a few
milliseconds a point takes tens of seconds; a descent at 2 m/s moves tens of metres). Each
beam then leaves from the platform's position at its firing time
(:func:`simlunar.lidar.steering.point_times`) and its point is ``position(t) + R d``: with the
pose known exactly (navigation), the cloud lands on the terrain; with one pose for the whole
scan, it is smeared by the motion. The velocity is constant (hover: zero). The line of sight
is stabilised in the world frame up to an attitude jitter: a small rotation per axis, a sum of
``JITTER_TONES`` sinusoids of random phase and frequency up to ``jitter_bandwidth_hz`` with an
RMS of ``attitude_jitter_rad`` per axis (a stationary, band-limited process; an assumption of
its shape), seeded by ``jitter_seed``.

:class:`Navigation` is what the sensor knows of its pose when it places its points
(:func:`place_points`): ``"exact"`` (the true pose at each firing), ``"noisy"`` (the true
pose plus white navigation errors per point, ``position_noise_m`` per axis and
``attitude_noise_rad`` per axis, from the point's own ``rng``) or ``"start"`` (no motion
compensation: the pose at the trajectory's start, t = 0, no jitter; in every round of a
multi-round scan). :func:`camera_at` is a co-boresighted device (flash receiver, micromirror
projector) carried by the platform: moved to its position at a time and turned by the jitter
then.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.errors import PlatformGroundedError
from simlunar.geometry import Camera, Pose
from simlunar.registry import Options, option, shared_option

__all__ = [
    "JITTER_TONES",
    "MOTION_OPTIONS",
    "Flight",
    "Navigation",
    "PlatformMotion",
    "Trajectory",
    "camera_at",
    "check_airborne",
    "place_points",
    "rotate_small",
]

#: sinusoids summed into each axis's attitude jitter
JITTER_TONES = 8
#: what the sensor knows of its pose (:class:`Navigation`)
COMPENSATIONS = ("exact", "noisy", "start")


@dataclass(frozen=True)
class Navigation(Options):
    """What the sensor knows of its pose when it places its points (module docstring)."""

    compensation: str = option(
        "exact",
        doc="exact: the true pose at each firing; noisy: plus white navigation errors per point; "
        "start: the pose at the trajectory's start (no motion compensation)",
        choices=COMPENSATIONS,
    )
    position_noise_m: float = option(
        0.0, doc="noisy: RMS position error per axis (at most 1 km)", unit="m", ge=0, le=1e3
    )
    attitude_noise_rad: float = option(
        0.0, doc="noisy: RMS pointing knowledge error per axis (at most 0.1 rad)", unit="rad",
        key_unit="urad", ge=0, le=0.1,
    )  # fmt: skip


#: the motion options that :class:`Trajectory`, :class:`Flight` and :class:`PlatformMotion`
#: declare alike: name -> keywords of :func:`simlunar.registry.option` (for
#: :func:`simlunar.registry.shared_option`)
MOTION_OPTIONS: dict[str, dict] = {
    "velocity_m_s": dict(
        default=(0.0, 0.0, 0.0),
        doc="constant velocity (3,) in the world frame; (0, 0, -2) is a 2 m/s descent, zero a "
        "hover",
        unit="m/s",
    ),
    "attitude_jitter_rad": dict(
        default=0.0,
        doc="RMS line-of-sight jitter per axis (0: none; at most 0.1 rad)",
        unit="rad",
        key_unit="urad",
        ge=0,
        le=0.1,
    ),
    "jitter_bandwidth_hz": dict(
        default=10.0,
        doc="highest frequency of the jitter (at most 1e5)",
        unit="Hz",
        gt=0,
        le=1e5,
    ),
    "navigation": dict(
        default=Navigation(),
        doc="how the points are placed (place_points); default the pose known exactly",
    ),
    "retarget": dict(
        default=True,
        doc="steered beam only (simlunar.lidar.scan.steered_beam_scan): command each beam from "
        "where the platform is towards where its planned direction (from the start) meets the "
        "gate's reference plane; False: hold the planned directions in the world frame",
    ),
}


def _vector3(name: str, value) -> np.ndarray:
    """``value`` as a read-only (3,) float array; a ``ValueError`` naming ``name`` unless it
    is 3 finite numbers."""
    v = np.asarray(value, float)
    if v.shape != (3,) or not np.isfinite(v).all():
        raise ValueError(f"{name} must be 3 finite numbers, got {value}")
    v.setflags(write=False)
    return v


@dataclass(frozen=True, eq=False)
class Trajectory(Options):
    """Constant-velocity motion of the sensor (world frame)."""

    position_m: tuple = option((0.0, 0.0, 0.0), doc="position (3,) at t = 0", unit="m")
    velocity_m_s: tuple = shared_option(MOTION_OPTIONS, "velocity_m_s")
    attitude_jitter_rad: float = shared_option(MOTION_OPTIONS, "attitude_jitter_rad")
    jitter_bandwidth_hz: float = shared_option(MOTION_OPTIONS, "jitter_bandwidth_hz")
    jitter_seed: int = option(0, doc="seed of the jitter's phases and frequencies")

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("position_m", "velocity_m_s"):
            object.__setattr__(self, name, _vector3(name, getattr(self, name)))

    @classmethod
    def hover(cls, position_m) -> Trajectory:
        """Holding ``position_m``."""
        return cls(position_m, (0.0, 0.0, 0.0))

    @classmethod
    def descent(
        cls, position_m, rate_m_s: float, horizontal_m_s=(0.0, 0.0), **jitter
    ) -> Trajectory:
        """Descending at ``rate_m_s`` (> 0: down) with a horizontal drift (m/s); ``jitter``:
        the attitude jitter fields."""
        h = np.asarray(horizontal_m_s, float).reshape(2)
        return cls(position_m, (h[0], h[1], -float(rate_m_s)), **jitter)

    def attitude_at(self, times_s) -> np.ndarray:
        """Line-of-sight jitter as small rotation vectors (..., 3) (rad) at ``times_s``."""
        t = np.asarray(times_s, float)
        if self.attitude_jitter_rad == 0:
            return np.zeros((*t.shape, 3))
        g = np.random.default_rng(self.jitter_seed)
        f = g.uniform(0.0, self.jitter_bandwidth_hz, (3, JITTER_TONES))
        ph = g.uniform(0.0, 2 * np.pi, (3, JITTER_TONES))
        amp = self.attitude_jitter_rad * np.sqrt(2.0 / JITTER_TONES)  # RMS per axis
        arg = 2 * np.pi * f * t[..., None, None] + ph
        return amp * np.cos(arg).sum(axis=-1)

    def at(self, times_s) -> np.ndarray:
        """Positions (..., 3) (m) at ``times_s`` (...) (s)."""
        t = np.asarray(times_s, float)[..., None]
        return self.position_m + t * self.velocity_m_s


def check_airborne(trajectory: Trajectory, times_s, datum_z: float, clearance_m: float, *,
                   what: str = "scan") -> None:  # fmt: skip
    """Refuse a scan whose platform is not at least ``clearance_m`` above the datum plane
    ``z = datum_z`` at every firing time ``times_s`` (s): a descent that lands (or passes
    through the ground) before the scan ends.

    Raises
    ------
    PlatformGroundedError
        Naming when the platform reaches the clearance and how long the scan is.
    """
    t = np.asarray(times_s, float).ravel()
    if t.size == 0:
        return
    low = trajectory.at(t)[:, 2] - float(datum_z) < clearance_m
    if low.any():
        first = float(t[np.argmax(low)])
        raise PlatformGroundedError(
            f"the platform descends to within {clearance_m:g} m of the ground (datum z = "
            f"{datum_z:.3g} m) {first:.3g} s into a {float(t.max()):.3g} s {what}: a scan "
            "this long needs a slower descent, a higher start or fewer samples"
        )


def rotate_small(vectors: np.ndarray, rotvec: np.ndarray) -> np.ndarray:
    """Rotate ``vectors`` (n, 3) by rotation vectors ``rotvec`` (n, 3) (rad; Rodrigues, exact)."""
    v = np.asarray(vectors, float)
    w = np.asarray(rotvec, float)
    th = np.linalg.norm(w, axis=-1, keepdims=True)
    k = np.divide(w, th, out=np.zeros_like(w), where=th > 0)
    c, s = np.cos(th), np.sin(th)
    return v * c + np.cross(k, v) * s + k * (k * v).sum(-1, keepdims=True) * (1 - c)


def camera_at(camera: Camera, trajectory: Trajectory, t: float) -> Camera:
    """``camera`` carried by the platform: at ``trajectory``'s position at time ``t`` (s), its
    axes turned by the attitude jitter then (the line of sight is held in the world frame up
    to the jitter, so ``camera``'s own position is replaced and its orientation kept)."""
    w = np.broadcast_to(trajectory.attitude_at(t), (3, 3))
    axes = rotate_small(np.asarray(camera.pose.rotation, float).T, w).T
    return Camera(camera.intrinsics, Pose(axes, trajectory.at(t)))


@dataclass(frozen=True)
class Flight(Options):
    """A scan measured from a moving platform: the trajectory it flies, what the sensor knows
    of its pose, and when on the trajectory the scan starts."""

    trajectory: Trajectory = option(
        doc="each beam or frame leaves from the platform's position at its firing time, turned "
        "by the line of sight's attitude jitter then"
    )
    navigation: Navigation = shared_option(MOTION_OPTIONS, "navigation")
    start_s: float = option(
        0.0,
        doc="when the scan's first beam or frame fires on the trajectory: a later round of a "
        "multi-round acquisition continues where the previous one ended. The scan's times and "
        "seconds stay counted from its own start",
        unit="s",
        ge=0,
    )
    retarget: bool = shared_option(MOTION_OPTIONS, "retarget")


def place_points(
    ranges: np.ndarray,
    commanded: np.ndarray,
    times_s: np.ndarray,
    trajectory: Trajectory,
    navigation: Navigation = Navigation(),
    *,
    rng=None,
) -> np.ndarray:
    """World points (n, 3) (m) of ranges measured along commanded directions, as the sensor
    places them with its pose knowledge.

    Parameters
    ----------
    ranges : (n,) float
        Slant ranges (m; NaN where invalid).
    commanded : (n, 3) float
        Unit directions the beam was commanded to (world frame, before jitter).
    times_s : (n,) float
        Firing times (s).
    trajectory : Trajectory
        The true motion (its jitter is what ``exact`` and ``noisy`` know).
    navigation : Navigation
    rng : seed or Generator
        ``noisy``: the navigation errors.

    Returns
    -------
    (n, 3) float64
    """
    r = np.asarray(ranges, float)[:, None]
    d = np.asarray(commanded, float)
    t = np.asarray(times_s, float)
    if navigation.compensation == "start":
        return trajectory.at(np.zeros_like(t)) + r * d
    pos, att = trajectory.at(t), trajectory.attitude_at(t)
    if navigation.compensation == "noisy":
        g = np.random.default_rng(rng)
        pos = pos + g.normal(0.0, navigation.position_noise_m, pos.shape)
        att = att + g.normal(0.0, navigation.attitude_noise_rad, att.shape)
    return pos + r * rotate_small(d, att)


@dataclass(frozen=True)
class PlatformMotion(Options):
    """A sensor's motion from wherever it starts: what a study configures (the start is the
    guide camera's centre; the jitter's phases are drawn per acquisition)."""

    velocity_m_s: tuple = shared_option(MOTION_OPTIONS, "velocity_m_s")
    attitude_jitter_rad: float = shared_option(MOTION_OPTIONS, "attitude_jitter_rad")
    jitter_bandwidth_hz: float = shared_option(MOTION_OPTIONS, "jitter_bandwidth_hz")
    navigation: Navigation = shared_option(MOTION_OPTIONS, "navigation")
    retarget: bool = shared_option(MOTION_OPTIONS, "retarget")

    def __post_init__(self) -> None:
        super().__post_init__()
        _vector3("velocity_m_s", self.velocity_m_s)

    def trajectory(self, start_m, *, jitter_seed: int = 0) -> Trajectory:
        """The trajectory from ``start_m`` (3,) m."""
        return Trajectory(start_m, self.velocity_m_s, self.attitude_jitter_rad,
                          self.jitter_bandwidth_hz, int(jitter_seed))  # fmt: skip
