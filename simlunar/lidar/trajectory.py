"""The platform's trajectory: where the sensor is when each pulse fires.

A lander hovering or descending moves while a steered beam scans (a 10 000-point scan at a few
milliseconds a point takes tens of seconds; a descent at 2 m/s moves tens of metres). Each
beam then leaves from the platform's position at its firing time
(:func:`simlunar.lidar.steering.point_times`) and its point is ``position(t) + R d``: with the
pose known exactly (navigation), the cloud lands on the terrain; with one pose for the whole
scan, it is smeared by the motion. Attitude is held constant (a gimbal stabilised in the
world frame); the velocity is constant (hover: zero).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Trajectory"]


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Constant-velocity motion of the sensor (world frame).

    Parameters
    ----------
    position_m : (3,) float
        Position at ``t = 0`` (m).
    velocity_m_s : (3,) float
        Velocity (m/s); zero = hover.
    """

    position_m: tuple = (0.0, 0.0, 0.0)
    velocity_m_s: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        for name in ("position_m", "velocity_m_s"):
            v = np.asarray(getattr(self, name), float)
            if v.shape != (3,) or not np.isfinite(v).all():
                raise ValueError(f"{name} must be 3 finite numbers, got {getattr(self, name)}")
            v.setflags(write=False)
            object.__setattr__(self, name, v)

    @classmethod
    def hover(cls, position_m) -> Trajectory:
        """Holding ``position_m``."""
        return cls(position_m, (0.0, 0.0, 0.0))

    @classmethod
    def descent(cls, position_m, rate_m_s: float, horizontal_m_s=(0.0, 0.0)) -> Trajectory:
        """Descending at ``rate_m_s`` (> 0: down) with a horizontal drift (m/s)."""
        h = np.asarray(horizontal_m_s, float).reshape(2)
        return cls(position_m, (h[0], h[1], -float(rate_m_s)))

    def at(self, times_s) -> np.ndarray:
        """Positions (..., 3) (m) at ``times_s`` (...) (s)."""
        t = np.asarray(times_s, float)[..., None]
        return self.position_m + t * self.velocity_m_s
