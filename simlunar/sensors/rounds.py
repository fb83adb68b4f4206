"""The rounds of a multi-round acquisition on a moving platform, one after the other.

A multi-round planner (:class:`~simlunar.study.lidar_planners.LidarRounds`) has the LIDAR
measure round after round; on a moving platform (:mod:`simlunar.lidar.trajectory`) the rounds
continue one trajectory instead of each starting it again at t = 0. :class:`PlatformRounds`
keeps that clock for any sensor that ranges planned cells.
"""

from __future__ import annotations

import numpy as np

from simlunar.sensors.base import Acquisition

__all__ = ["PlatformRounds", "platform_trajectory"]


def platform_trajectory(camera, motion, rng):
    """The trajectory of ``motion`` (a :class:`~simlunar.lidar.trajectory.PlatformMotion`)
    from ``camera``'s centre at t = 0, its jitter phases drawn from ``rng`` (a Generator);
    None at rest (``motion`` None)."""
    if motion is None:
        return None
    return motion.trajectory(camera.position, jitter_seed=int(rng.integers(2**31)))


class PlatformRounds:
    """The rounds of one multi-round acquisition of a LIDAR that ranges planned cells (the
    steered beam, the micromirror flash), measured one after the other: ``rounds(rc)`` ranges round ``rc`` ((m, 2) planned guide pixels) and returns its
    :class:`~simlunar.sensors.base.Acquisition` (what
    :class:`~simlunar.study.lidar_planners.LidarRounds` measures through).

    At rest every round is the sensor's ``acquire`` with the same generator. On a moving
    platform (``SteeredBeamOptions.motion``) the rounds continue one trajectory (from the
    guide camera at t = 0, its jitter phases drawn once): round ``r`` starts when round
    ``r - 1`` ended plus the re-pointing from its last visited beam to this round's first
    (the sensor's ``round_gap_seconds``: a steered beam's move and settle to the first beam
    the scan visits; a sensor without one, the micromirror, switches at once), so its beams
    leave from where the platform is then; its points are placed with the sensor's navigation (``start``: from the pose at
    t = 0 in every round) and scored where they project in the guide view.

    Parameters
    ----------
    sensor : SteeredBeam or MicromirrorFlash
        With ``trajectory(rng)``, ``acquire`` and ``_moving(rc, rng, trajectory, start_s)``.
    rng : seed or Generator
        Photon noise of every round and the trajectory's jitter phases.

    Attributes
    ----------
    trajectory : Trajectory or None
        The platform's motion (None at rest).
    starts_s : list of float
        When each round measured so far started (s on the trajectory; empty at rest).
    gaps_s : list of float or None
        The re-pointing (s) before each later round, as the start times count it; None at
        rest (:func:`~simlunar.study.lidar_planners.merge_rounds` prices it itself).
    """

    def __init__(self, sensor, rng=None) -> None:
        self.sensor = sensor
        self.rng = np.random.default_rng(rng)
        self.trajectory = sensor.trajectory(self.rng)
        self.starts_s: list[float] = []
        self.gaps_s: list[float] | None = None if self.trajectory is None else []
        self._end_s, self._last = 0.0, None

    def __call__(self, rc: np.ndarray) -> Acquisition:
        """The acquisition of this round's planned guide pixels ``rc`` (m, 2)."""
        if self.trajectory is None:
            return self.sensor.acquire(rc, rng=self.rng)
        rc = np.asarray(rc).reshape(-1, 2)
        start = self._end_s
        if self._last is not None:
            gap_of = getattr(self.sensor, "round_gap_seconds", None)
            gap = 0.0 if gap_of is None else float(gap_of(self._last, rc))
            self.gaps_s.append(gap)
            start += gap
        acq = self.sensor._moving(rc, self.rng, self.trajectory, start)
        self.starts_s.append(start)
        self._end_s = start + acq.seconds
        self._last = rc[np.asarray(acq.detail.order).ravel()[-1]]
        return acq
