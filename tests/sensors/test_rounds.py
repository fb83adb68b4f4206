"""The rounds of a multi-round acquisition on a moving platform (simlunar.sensors.rounds):
the micromirror's rounds continue the trajectory; at rest a round is the sensor's acquire."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar import DetectorOptions, PulseOptions
from simlunar.sensors.rounds import PlatformRounds, platform_trajectory
from simlunar.terrain import Terrain

H = 50.0


def _plane() -> Terrain:
    return Terrain(heights=np.zeros((80, 80)), albedo=np.full((80, 80), 0.2, np.float32),
                   spacing=1.0, origin=(-40.0, 40.0))  # fmt: skip


def _camera() -> Camera:
    pose = Pose.look_at([0.0, 0.0, H], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    return Camera(Intrinsics.from_fov(32, 32, 6.0), pose)


class _Clocked:
    """A stand-in sensor: each round takes 0.5 s per cell; ``_moving`` records its start."""

    def __init__(self, gap=None):
        self.starts, self.at_rest = [], 0
        if gap is not None:
            self.round_gap_seconds = lambda last, rc: gap

    def trajectory(self, rng):
        return "trajectory"

    def acquire(self, rc, *, rng=None):
        self.at_rest += 1
        return self._acq(rc)

    def _moving(self, rc, rng, trajectory, start_s):
        assert trajectory == "trajectory"
        self.starts.append(start_s)
        return self._acq(rc)

    @staticmethod
    def _acq(rc):
        from types import SimpleNamespace

        from simlunar.sensors.base import Acquisition

        rc = np.asarray(rc).reshape(-1, 2)
        detail = SimpleNamespace(order=np.arange(len(rc)))
        return Acquisition(rc.astype(float), np.ones(len(rc)), (8, 8), seconds=0.5 * len(rc),
                           detail=detail)  # fmt: skip


def test_rounds_start_where_the_previous_ended_plus_the_gap():
    # rounds of 2, 3 and 1 cells (1.0, 1.5, 0.5 s): with a 0.25 s gap they start at 0,
    # 1.25 and 3.0 s; a sensor without round_gap_seconds (the micromirror) switches at once
    rounds = PlatformRounds(_Clocked(gap=0.25), rng=0)
    for rc in ([[0, 0], [1, 1]], [[2, 2], [3, 3], [4, 4]], [[5, 5]]):
        rounds(rc)
    assert rounds.starts_s == pytest.approx([0.0, 1.25, 3.0])
    assert rounds.gaps_s == [0.25, 0.25]
    free = PlatformRounds(_Clocked(), rng=0)
    for rc in ([[0, 0], [1, 1]], [[2, 2], [3, 3], [4, 4]]):
        free(rc)
    assert free.starts_s == pytest.approx([0.0, 1.0]) and free.gaps_s == [0.0]


def test_at_rest_a_round_is_the_sensor_s_acquire():
    sensor = _Clocked()
    sensor.trajectory = lambda rng: None
    rounds = PlatformRounds(sensor, rng=0)
    rounds([[0, 0]])
    rounds([[1, 1]])
    assert sensor.at_rest == 2 and sensor.starts == []
    assert rounds.starts_s == [] and rounds.gaps_s is None


def test_platform_trajectory_is_none_at_rest_and_draws_its_jitter_once():
    from simlunar.lidar.trajectory import PlatformMotion

    assert platform_trajectory(_camera(), None, np.random.default_rng(0)) is None
    motion = PlatformMotion((0.0, 0.0, -10.0))
    g = np.random.default_rng(3)
    traj = platform_trajectory(_camera(), motion, g)
    np.testing.assert_allclose(np.asarray(traj.at(1.0)).ravel(), [0.0, 0.0, H - 10.0])
    # one draw of the generator: the jitter's seed
    ref = np.random.default_rng(3)
    assert traj.jitter_seed == int(ref.integers(2**31))
    assert g.integers(1 << 30) == ref.integers(1 << 30)


@pytest.mark.render
def test_a_descending_micromirror_s_second_round_fires_when_the_first_ended(mi):
    # 10 m/s straight down over the z = 0 plane from 50 m; round 1 (3 dots sharing a
    # receiver pixel: 3 frames of 4 pulses at 20 Hz, 0.6 s) then round 2 (one frame). The
    # mirrors switch at once, so round 2 fires at t = 0.6 s, from 44 m. Placed from the pose
    # at t = 0 ("start"), a dot of frame f of round r sits 10 m/s x (start_r + 0.2 f) above
    # the plane; with the exact pose every point is on it (a range bin, 5 cm)
    from simlunar.lidar.flash import FlashOptions
    from simlunar.lidar.trajectory import Navigation, PlatformMotion
    from simlunar.render.transient import TransientOptions
    from simlunar.sensors import LidarScene, MicromirrorFlash, MicromirrorOptions

    det = DetectorOptions(signal_photons=2e6 * 16, background_photons_per_s=0.0, pulses=4)
    flash = FlashOptions(detector=det, pulse=PulseOptions(fwhm_s=1e-9),
                         transient=TransientOptions(spp=256), pulse_rate_hz=20.0)  # fmt: skip
    first = np.array([[0, 0], [1, 2], [3, 3]])  # one receiver pixel: 3 frames
    second = np.array([[20, 20], [9, 25]])  # one frame

    def run(compensation):
        motion = PlatformMotion((0.0, 0.0, -10.0), navigation=Navigation(compensation))
        sensor = MicromirrorFlash(LidarScene(_plane(), _camera()),
                                  MicromirrorOptions(flash, receiver_px=(8, 8), motion=motion))  # fmt: skip
        rounds = sensor.rounds(rng=0)
        return rounds, [rounds(first), rounds(second)]

    rounds, (a, b) = run("exact")
    assert a.frames == 3 and a.seconds == pytest.approx(0.6) and b.frames == 1
    assert rounds.starts_s == pytest.approx([0.0, 0.6]) and rounds.gaps_s == [0.0]
    for acq in (a, b):
        assert acq.detail.points[acq.detail.valid, 2] == pytest.approx(0.0, abs=0.05)
    rounds, (a, b) = run("start")
    lift_a = 10.0 * (0.0 + a.detail.times)  # each dot's frame: 0, 0.2, 0.4 s
    assert sorted(a.detail.times) == pytest.approx([0.0, 0.2, 0.4])
    assert a.detail.points[:, 2] == pytest.approx(lift_a, abs=0.05)
    assert b.detail.points[:, 2] == pytest.approx(10.0 * 0.6, abs=0.05)
