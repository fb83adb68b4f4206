"""The LIDAR study's planners with stand-in sensors (no rendering): the oracles read the true
depth in the planner step only and aim where the true error is; multi-round planning asks the
sensor back, steers by what it measured, and its time is every round's plus the re-pointing."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar.returns import LidarScan
from simlunar.planner import SequentialOptions
from simlunar.sensors import Acquisition, LidarScene
from simlunar.study.lidar import LidarStudyOptions, SensorFit, run_lidar_study
from simlunar.study.lidar_planners import LidarRounds, merge_rounds, planned_values
from simlunar.terrain import Terrain

N = 32


def _scene():
    terrain = Terrain(np.zeros((40, 40)), np.full((40, 40), 0.2, np.float32), 1.0, (-20.0, 20.0))
    pose = Pose.look_at([0.0, 0.0, 30.0], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    return LidarScene(terrain, Camera(Intrinsics.from_fov(N, N, 40.0), pose))


def _bump():
    """A plane at 30 m with a sharp bump in the top-left quadrant (rows, cols < 16)."""
    r, c = np.mgrid[0:N, 0:N]
    return 30.0 - 2.0 * np.exp(-((r - 8.0) ** 2 + (c - 8.0) ** 2) / 6.0)


class _Beam:
    """A stand-in steered beam: the true depth at the planned cells (NaN-free unless
    ``lost`` names cells it detects no return at), 1 ms per sample, visiting the cells in
    the plan's order, 0.5 s to re-point between scans, 2 mJ of laser energy per sample; it
    records what it was asked."""

    name = "beam"
    needs_plan = True

    def __init__(self, depth, lost=(), corrupt=None):
        self._depth = np.asarray(depth, float)
        self.lost = {tuple(x) for x in lost}
        self.corrupt = corrupt  # (rc) -> values override, for the first call only
        self.asked: list[np.ndarray] = []
        self.repoints: list[tuple] = []

    def acquire(self, rc, *, rng=None):
        rc = np.asarray(rc).reshape(-1, 2)
        self.asked.append(rc.copy())
        v = self._depth[rc[:, 0], rc[:, 1]]
        if self.corrupt is not None and len(self.asked) == 1:
            v = self.corrupt(rc, v)
        valid = np.array([tuple(x) not in self.lost for x in rc.tolist()])
        n = len(rc)
        scan = LidarScan(v, valid, np.zeros((n, 3)), np.ones(n), np.arange(n), 1e-3 * n, n,
                         times=1e-3 * np.arange(n))  # fmt: skip
        return Acquisition(rc[valid], v[valid], self._depth.shape, frames=n, seconds=1e-3 * n,
                           detail=scan, planned=rc, energy_j=2e-3 * n)  # fmt: skip

    def scan_seconds(self, rc):
        return 1e-3 * len(rc)

    def scan_energy_j(self, rc):
        return 2e-3 * len(rc)

    def repoint_seconds(self, a, b):
        self.repoints.append((tuple(a), tuple(b)))
        return 0.5


def _rows(rows, planner, metric="mse"):
    return [r for r in rows if r["planner"] == planner and r["metric"] == metric]


# --------------------------------------------------------------------------- oracles


@pytest.mark.parametrize("oracle", ["oracle_hessian", "oracle_greedy"])
def test_oracle_beams_land_where_the_true_error_is(oracle):
    depth = _bump()
    image = np.full((N, N), 0.5, np.float32)  # the image says nothing: only the truth can
    sensor = _Beam(depth)
    o = LidarStudyOptions(planners=("grid", oracle), densities=(1 / 16,), trials=1,
                          metrics=("mse",))  # fmt: skip
    rows = run_lidar_study(_scene(), (image, depth), o, rng=0, sensor=sensor).rows
    grid_rc, oracle_rc = sensor.asked
    # the bump covers a quarter of the view: the grid puts a quarter of its beams there, the
    # oracle (which read the true depth) well over half
    share = lambda rc: np.mean((rc[:, 0] < 16) & (rc[:, 1] < 16))  # noqa: E731
    assert share(grid_rc) == pytest.approx(0.25, abs=0.05)
    assert share(oracle_rc) > 0.5
    # the real sensor measured the oracle's beams as any planner's: same count, same cost
    assert len(oracle_rc) == len(grid_rc) == 64
    (g,), (b,) = _rows(rows, "grid"), _rows(rows, oracle)
    assert b["seconds"] == pytest.approx(0.064) and b["value"] < g["value"]


def test_an_oracle_needs_the_true_depth_everywhere():
    depth = _bump()
    depth[0, :3] = np.nan  # the view misses the terrain there
    o = LidarStudyOptions(planners=("oracle_hessian",), densities=(1 / 16,), trials=1)
    with pytest.raises(ValueError, match="3 pixels of the guide view miss the terrain"):
        run_lidar_study(_scene(), (np.full((N, N), 0.5), depth), o, rng=0,
                        sensor=_Beam(np.nan_to_num(depth, nan=30.0)))  # fmt: skip


def test_the_sensor_never_reads_the_truth_the_oracle_plans_from():
    # the sensor measures its own scene: a truth that differs from the sensor's scene changes
    # where the oracle aims, never what the sensor reports there
    depth = _bump()
    flat = np.full((N, N), 30.0)
    sensor = _Beam(flat)
    o = LidarStudyOptions(planners=("oracle_hessian",), densities=(1 / 16,), trials=1)
    res = run_lidar_study(_scene(), (depth.astype(np.float32), depth), o, rng=0, sensor=sensor)
    np.testing.assert_array_equal(res.examples["oracle_hessian"].values, 30.0)


# --------------------------------------------------------------------------- multi-round


def _rounds(k=64, **kw):
    opts = SequentialOptions(max_rounds=4, first_share=0.4, batch_share=0.2, **kw)
    return LidarRounds(opts, None, (N, N))


def test_the_second_round_follows_the_first_round_s_measured_ranges():
    depth = np.full((N, N), 30.0)
    clean = _Beam(depth)
    _, rounds = _rounds().acquire(64, clean, 1, 2)
    assert rounds == len(clean.asked) == 4

    def spike(rc, v):  # a corrupted first-round range near (24, 24)
        v = v.copy()
        v[np.argmin(np.hypot(rc[:, 0] - 24, rc[:, 1] - 24))] += 5.0
        return v

    corrupted = _Beam(depth, corrupt=spike)
    _rounds().acquire(64, corrupted, 1, 2)
    # same first round (same seed, same layout), a different second round, aimed at the spike
    np.testing.assert_array_equal(corrupted.asked[0], clean.asked[0])
    assert not np.array_equal(np.sort(corrupted.asked[1], 0), np.sort(clean.asked[1], 0))
    d = lambda rc: np.hypot(rc[:, 0] - 24, rc[:, 1] - 24).mean()  # noqa: E731
    assert d(corrupted.asked[1]) < d(clean.asked[1])


def test_rounds_time_adds_up_with_the_repointing_between_them():
    sensor = _Beam(_bump())
    acq, rounds = _rounds().acquire(64, sensor, 1, 2)
    sizes = [len(rc) for rc in sensor.asked]
    assert sum(sizes) == 64 == len(acq.values) and len(sizes) == rounds
    # 1 ms per sample over every round + 0.5 s per re-pointing between rounds
    assert acq.seconds == pytest.approx(64e-3 + 0.5 * (rounds - 1))
    assert acq.frames == 64
    # each re-pointing goes from the last cell of one round to the first of the next
    for (a, b), before, after in zip(sensor.repoints, sensor.asked, sensor.asked[1:]):
        assert a == tuple(before[-1]) and b == tuple(after[0])
    # the joined scan's times run on across rounds: round 2 starts after round 1 + 0.5 s
    t = acq.detail.times
    assert t[sizes[0]] == pytest.approx(sizes[0] * 1e-3 + 0.5)
    assert acq.detail.seconds == pytest.approx(acq.seconds)


def test_a_lost_return_is_a_cell_taken_but_not_measured():
    depth = _bump()
    first = _Beam(depth)
    _rounds().acquire(64, first, 1, 2)
    lost = first.asked[0][:3]
    sensor = _Beam(depth, lost=lost)
    acq, _ = _rounds().acquire(64, sensor, 1, 2)
    assert len(acq.values) == 61 and len(acq.planned) == 64
    asked = np.concatenate(sensor.asked)
    assert len({tuple(x) for x in asked.tolist()}) == 64  # never asked twice


def test_planned_values_put_nan_where_no_return_came_back():
    rc = np.array([[0, 0], [1, 1], [2, 2]])
    scan = LidarScan(np.ones(3), np.array([True, False, True]), np.zeros((3, 3)), np.ones(3),
                     np.arange(3), 0.0, 3)  # fmt: skip
    acq = Acquisition(rc[[0, 2]], np.array([5.0, 7.0]), (4, 4), detail=scan, planned=rc)
    np.testing.assert_array_equal(planned_values(acq, 3), [5.0, np.nan, 7.0])
    with pytest.raises(ValueError, match="one sample per planned cell"):
        planned_values(acq, 4)


def test_merge_rounds_without_a_repointing_model_sums_the_rounds():
    a = Acquisition(np.zeros((2, 2)), np.ones(2), (4, 4), frames=2, seconds=0.25)
    b = Acquisition(np.ones((1, 2)), np.ones(1), (4, 4), frames=1, seconds=0.5)
    m = merge_rounds([a, b], object())
    assert m.seconds == 0.75 and m.frames == 3 and len(m.values) == 3 and m.detail is None


def test_a_study_row_of_sequential_counts_every_round():
    depth = _bump()
    o = LidarStudyOptions(planners=("grid", "sequential"), densities=(1 / 16,), trials=1,
                          metrics=("mse",),
                          planner_opts={"sequential": {"sequential": SequentialOptions(4)}})  # fmt: skip
    rows = run_lidar_study(_scene(), (depth.astype(np.float32), depth), o, rng=0,
                           sensor=_Beam(depth)).rows  # fmt: skip
    (s,) = _rows(rows, "sequential")
    (g,) = _rows(rows, "grid")
    assert s["rounds"] >= 2 and "rounds" not in g
    assert s["seconds"] == pytest.approx(64e-3 + 0.5 * (s["rounds"] - 1))
    assert g["seconds"] == pytest.approx(64e-3)
    # every round fires its pulses: the energy adds up (2 mJ per sample, 64 samples)
    assert s["energy_j"] == pytest.approx(64 * 2e-3) and g["energy_j"] == pytest.approx(64 * 2e-3)


def test_budget_fits_put_planners_at_equal_time_or_equal_energy_whatever_the_density():
    # 1 ms and 2 mJ per sample: 20 ms holds 20 samples, 30 mJ 15, both together 15; at 1/16
    # (64 samples) and 1/64 (16) alike, since the budget is absolute
    depth = _bump()
    fits = {"at_time": SensorFit("budget", budget_s=0.02),
            "at_energy": SensorFit("budget", budget_j=0.03),
            "at_both": SensorFit("budget", budget_s=0.02, budget_j=0.03)}  # fmt: skip
    o = LidarStudyOptions(planners=("grid", *fits), densities=(1 / 64, 1 / 16), trials=1,
                          metrics=("mse",), strategies=dict.fromkeys(fits, "lloyd_uniform"),
                          fits=fits)  # fmt: skip
    rows = run_lidar_study(_scene(), (depth.astype(np.float32), depth), o, rng=0,
                           sensor=_Beam(depth)).rows  # fmt: skip
    for label, n in (("at_time", 20), ("at_energy", 15), ("at_both", 15)):
        got = _rows(rows, label)
        assert [r["samples"] for r in got] == [n, n]
        assert all(r["energy_j"] == pytest.approx(2e-3 * n) for r in got)
    assert [r["samples"] for r in _rows(rows, "grid")] == [16, 64]
    # a budget under three samples (the least a plan may have) gets three, over budget
    o = LidarStudyOptions(planners=("tiny",), densities=(1 / 16,), trials=1, metrics=("mse",),
                          strategies={"tiny": "lloyd_uniform"},
                          fits={"tiny": SensorFit("budget", budget_s=0.0015)})  # fmt: skip
    (r,) = _rows(run_lidar_study(_scene(), (depth.astype(np.float32), depth), o, rng=0,
                                 sensor=_Beam(depth)).rows, "tiny")  # fmt: skip
    assert r["samples"] == 3 and r["seconds"] == pytest.approx(3e-3)


def test_a_budget_fit_refuses_a_sensor_that_cannot_price_it():
    from simlunar.study.lidar_planners import budget_cost

    class _Timed:
        name = "timed"

        def scan_seconds(self, rc):
            return 1.0

    assert budget_cost(SensorFit("budget", budget_s=2.0), _Timed())(np.zeros((3, 2))) == 0.5
    with pytest.raises(ValueError, match="a budget fit needs a sensor with scan_energy_j"):
        budget_cost(SensorFit("budget", budget_j=1.0), _Timed())


def test_options_refuse_a_fitted_multi_round_planner():
    with pytest.raises(ValueError, match="multi-round planner is not fitted"):
        LidarStudyOptions(planners=("grid", "sequential"),
                          fits={"sequential": SensorFit("scan_time", "grid")})  # fmt: skip


def test_multi_round_refuses_a_flash():
    depth = _bump()
    beam = _Beam(depth)
    beam.name = "flash"
    o = LidarStudyOptions(planners=("sequential",), densities=(1 / 16,), trials=1)
    with pytest.raises(ValueError, match="flash LIDAR measures its receiver pixels"):
        run_lidar_study(_scene(), (depth.astype(np.float32), depth), o, rng=0, sensor=beam)


class _Moving(_Beam):
    """A stand-in moving beam: ``options.motion`` set; with ``rounds`` it measures a
    multi-round acquisition through its own round-by-round acquirer, which starts round r
    0.25 s after round r - 1 ended (its re-pointing) and records the starts."""

    def __init__(self, depth, *, with_rounds=True):
        super().__init__(depth)
        self.options = type("Opts", (), {"motion": object()})()
        self.starts: list[float] = []
        if with_rounds:
            self.rounds = self._rounds

    def _rounds(self, *, rng=None):
        return _Take(self, rng)


class _Take:
    """The rounds of one acquisition of a :class:`_Moving`."""

    def __init__(self, sensor, rng):
        self.sensor, self.rng, self.gaps_s, self.end = sensor, rng, [], None

    def __call__(self, rc):
        start = 0.0 if self.end is None else self.end + 0.25
        if self.end is not None:
            self.gaps_s.append(0.25)
        acq = self.sensor.acquire(rc, rng=self.rng)
        self.sensor.starts.append(start)
        self.end = start + acq.seconds
        return acq


def test_a_moving_sensor_s_rounds_are_measured_through_it_and_merged_with_its_repointing():
    sensor = _Moving(_bump())
    acq, rounds = _rounds().acquire(64, sensor, 1, 2)
    assert rounds == len(sensor.starts) >= 2
    # its own re-pointing (0.25 s) is counted, not the repoint_seconds of a sensor at rest
    assert sensor.repoints == []
    assert acq.seconds == pytest.approx(64e-3 + 0.25 * (rounds - 1))
    assert acq.detail.times[len(sensor.asked[0])] == pytest.approx(sensor.starts[1])


def test_multi_round_refuses_a_moving_sensor_whose_rounds_would_restart_the_trajectory():
    depth = _bump()
    o = LidarStudyOptions(planners=("sequential",), densities=(1 / 16,), trials=1)
    with pytest.raises(ValueError, match="needs a sensor whose rounds continue the platform"):
        run_lidar_study(_scene(), (depth.astype(np.float32), depth), o, rng=0,
                        sensor=_Moving(depth, with_rounds=False))  # fmt: skip


def test_merge_rounds_takes_one_repointing_per_pair_of_rounds():
    a = Acquisition(np.zeros((2, 2)), np.ones(2), (4, 4), frames=2, seconds=0.25)
    b = Acquisition(np.ones((1, 2)), np.ones(1), (4, 4), frames=1, seconds=0.5)
    assert merge_rounds([a, b], object(), gaps_s=[0.125]).seconds == 0.875
    with pytest.raises(ValueError, match="need 1 re-pointing times, got 2"):
        merge_rounds([a, b], object(), gaps_s=[0.1, 0.2])
