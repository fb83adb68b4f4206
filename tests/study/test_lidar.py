"""The LIDAR study through the protocol with a stand-in sensor (no rendering): rows carry
scan time and sample count; seeds are per (planner, trial, density)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.metrics.hazard import HazardOptions
from simlunar.sensors import Acquisition, LidarScene
from simlunar.study.lidar import LidarStudyOptions, SensorFit, run_lidar_study, time_table
from simlunar.terrain import Terrain


class _Timed:
    """The true depth at the planned pixels, 1 ms per sample."""

    name = "timed"

    def __init__(self, depth, needs_plan=True):
        self.depth = depth
        self.needs_plan = needs_plan

    def acquire(self, rc, *, rng=None):
        if rc is None:
            r, c = np.mgrid[0:32:4, 0:32:4]
            rc = np.stack([r.ravel(), c.ravel()], -1)
        v = self.depth[rc[:, 0], rc[:, 1]]
        return Acquisition(rc, v, self.depth.shape, frames=len(rc), seconds=1e-3 * len(rc))


def _scene():
    n = 40
    terrain = Terrain(np.zeros((n, n)), np.full((n, n), 0.2, np.float32), 1.0, (-20.0, 20.0))
    pose = Pose.look_at([0.0, 0.0, 30.0], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    return LidarScene(terrain, Camera(Intrinsics.from_fov(32, 32, 40.0), pose))


def _guide():
    r, c = np.mgrid[0:32, 0:32]
    depth = 30.0 + 0.5 * np.sin(r / 3.0) * np.cos(c / 4.0)
    return depth.astype(np.float32), depth


def test_rows_carry_seconds_frames_and_k():
    image, depth = _guide()
    o = LidarStudyOptions(planners=("random", "grid"), densities=(1 / 16, 1 / 64), trials=2)
    res = run_lidar_study(_scene(), (image, depth), o, rng=0, sensor=_Timed(depth))
    assert len(res.rows) == 2 * 2 * 2 * 3  # planners x densities x trials x (mse, grad, valid)
    for row in res.rows:
        assert row["seconds"] == pytest.approx(1e-3 * row["k"])
        assert row["frames"] == row["k"]
    assert {r["k"] for r in res.rows} == {64, 16}
    tab = time_table(res.rows)
    assert list(tab["grid"]["k"]) == [16, 64]
    assert tab["grid"]["seconds"] == pytest.approx([0.016, 0.064])
    assert set(res.examples) == {"random", "grid"}


def test_a_planner_never_changes_another_planners_numbers():
    image, depth = _guide()
    one = LidarStudyOptions(planners=("random",), densities=(1 / 16,), trials=2)
    two = LidarStudyOptions(planners=("grid", "random"), densities=(1 / 16,), trials=2)
    a = run_lidar_study(_scene(), (image, depth), one, rng=3, sensor=_Timed(depth)).rows
    b = run_lidar_study(_scene(), (image, depth), two, rng=3, sensor=_Timed(depth)).rows
    assert a == [r for r in b if r["planner"] == "random"]


def test_a_sensor_without_plan_runs_once_per_trial_as_none():
    image, depth = _guide()
    o = LidarStudyOptions(densities=(1 / 16, 1 / 4), trials=1, hazard=HazardOptions())
    rows = run_lidar_study(
        _scene(), (image, depth), o, rng=0, sensor=_Timed(depth, needs_plan=False)
    ).rows
    assert {r["planner"] for r in rows} == {"none"} and {r["k"] for r in rows} == {0}
    names = {r["metric"] for r in rows}
    assert {"hazard_precision", "hazard_recall", "valid_fraction"} <= names


def test_options_refuse_unknown_names():
    with pytest.raises(
        ValueError,
        match="sensor must be one of 'steered_beam', 'flash', 'micromirror_flash', got 'sonar'",
    ):
        LidarStudyOptions(sensor="sonar")
    with pytest.raises(ValueError, match="unknown planner"):
        LidarStudyOptions(planners=("psychic",))
    with pytest.raises(ValueError, match="must be FlashLidarOptions"):
        LidarStudyOptions(sensor="flash", sensor_options=HazardOptions())


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: LidarStudyOptions(trials=0), "trials must be >= 1, got 0"),
        (lambda: LidarStudyOptions(trials=True), "trials must be a finite number, got True"),
        (lambda: LidarStudyOptions(densities=(0.5, 0.0)), r"densities must be in \(0, 1\]"),
        (lambda: SensorFit("tour"), "kind must be one of 'scan_time', 'budget', 'receiver'"),
        (lambda: SensorFit("budget"), "a budget fit needs budget_s, budget_j or both"),
        (lambda: SensorFit("scan_time", budget_s=1.0), "are for a budget fit, not 'scan_time'"),
        (lambda: SensorFit("budget", budget_j=0.0), "budget_j must be > 0, got 0.0"),
        (lambda: SensorFit("receiver", frames=0), "frames must be >= 1, got 0"),
    ],
)
def test_options_refuse_bad_values(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_equal_time_errors_interpolate_in_log_log():
    from simlunar.study.lidar import equal_time_errors

    rows = [
        {"unit": u, "planner": "grid", "k": k, "metric": "mse", "value": v * (1 + u), "seconds": s}
        for u in (0, 1)
        for k, s, v in ((10, 1.0, 1e-2), (100, 10.0, 1e-3))
    ]
    e = equal_time_errors(rows, [np.sqrt(10.0), 20.0])["grid"]
    assert e.shape == (2, 2)
    assert e[:, 0] == pytest.approx([10**-2.5, 2 * 10**-2.5])
    assert np.isnan(e[:, 1]).all()  # beyond the longest scan


def test_every_reconstruction_gets_rows_and_tables_read_one():
    image, depth = _guide()
    o = LidarStudyOptions(
        planners=("grid",), densities=(1 / 16,), trials=1,
        reconstructions={"linear": {"outside": "nearest"}},
    )  # fmt: skip
    res = run_lidar_study(_scene(), (image, depth), o, rng=0, sensor=_Timed(depth))
    assert {r["reconstruction"] for r in res.rows} == {"linear"}
    rows = res.rows + [{**r, "reconstruction": "other", "value": 1e9} for r in res.rows]
    # the other reconstruction's rows are not pooled into linear's
    assert time_table(rows)["grid"]["value"] == pytest.approx(time_table(res.rows)["grid"]["value"])
    assert time_table(rows, reconstruction="other")["grid"]["value"] == pytest.approx([1e9])


class _Noisy(_Timed):
    """The stand-in with photon noise from the acquisition's rng; counts its acquisitions."""

    def __init__(self, depth, stop_at=None):
        super().__init__(depth)
        self.calls, self.stop_at = 0, stop_at

    def acquire(self, rc, *, rng=None):
        self.calls += 1
        if self.calls == self.stop_at:
            raise KeyboardInterrupt
        acq = super().acquire(rc)
        noise = np.random.default_rng(rng).normal(0, 0.01, len(acq.values))
        return Acquisition(acq.rc, acq.values + noise, acq.shape, acq.frames, acq.seconds)


def test_a_study_cut_short_at_its_second_planner_resumes_exactly():
    from simlunar.progress import reporting
    from simlunar.study.steps import MemorySteps

    image, depth = _guide()
    o = LidarStudyOptions(planners=("random", "grid", "wavelet"), densities=(1 / 16,), trials=2)
    clean = run_lidar_study(_scene(), (image, depth), o, rng=4, sensor=_Noisy(depth))
    steps = MemorySteps()
    with pytest.raises(KeyboardInterrupt):  # at the second planner's first acquisition
        run_lidar_study(_scene(), (image, depth), o, rng=4, sensor=_Noisy(depth, 3), steps=steps)
    assert list(steps.saved) == ["lidar planner random"]
    sensor, events = _Noisy(depth), []
    with reporting(events.append):
        resumed = run_lidar_study(_scene(), (image, depth), o, rng=4, sensor=sensor, steps=steps)
    assert sensor.calls == 4  # grid and wavelet, two trials each: random was kept
    assert resumed.rows == clean.rows
    np.testing.assert_array_equal(
        resumed.examples["random"].values, clean.examples["random"].values
    )
    study = [e for e in events if e.path == ("lidar study",)]
    assert (study[0].done, study[0].total, study[0].unit) == (0, 6, "acquisitions")
    assert [e.done for e in study[1:]] == [2, 3, 4, 5, 6, 6] and study[-1].finished


def test_beam_table_lists_every_beam_in_visiting_order():
    from simlunar.lidar.returns import LidarScan
    from simlunar.study.lidar import beam_table

    planned = np.array([[0, 0], [0, 5], [3, 5], [3, 0]])
    valid = np.array([True, False, True, True])
    pts = np.zeros((4, 3))
    times = np.array([0.0, 0.3, 0.2, 0.1])
    order = np.array([0, 3, 2, 1])  # visited 0, 3, 2, 1: times ascending
    scan = LidarScan(np.ones(4), valid, pts, np.ones(4), order, 0.4, 4, times=times)
    acq = Acquisition(planned[valid], np.array([10.0, 12.0, 13.0]), (4, 6), detail=scan,
                      planned=planned)  # fmt: skip
    t = beam_table(acq)
    assert t.shape == (4, 4)
    np.testing.assert_array_equal(t[:, :2], planned[order])
    np.testing.assert_array_equal(t[:, 2], [0.0, 0.1, 0.2, 0.3])
    # beam 1 returned nothing: NaN depth, still in the tour
    np.testing.assert_array_equal(t[:, 3], [10.0, 13.0, 12.0, np.nan])


def test_beam_table_of_a_flash_places_the_measured_pixels():
    from simlunar.lidar.returns import LidarScan
    from simlunar.study.lidar import beam_table

    valid = np.array([True, True, False])
    scan = LidarScan(np.ones(3), valid, np.zeros((3, 3)), np.ones(3), np.arange(3), 0.1, 1)
    acq = Acquisition(np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([5.0, 6.0]), (8, 8),
                      detail=scan)  # fmt: skip
    t = beam_table(acq)
    np.testing.assert_array_equal(t[:2], [[1, 2, np.nan, 5], [3, 4, np.nan, 6]])
    assert np.isnan(t[2]).all()  # a receiver pixel without a return has no guide position
    bad = Acquisition(np.zeros((1, 2)), np.array([1.0]), (8, 8), detail=scan)
    with pytest.raises(ValueError, match="2 valid samples"):
        beam_table(bad)


def test_beam_table_of_a_multi_frame_flash_runs_frame_after_frame():
    from simlunar.lidar.returns import LidarScan
    from simlunar.study.lidar import beam_table

    planned = np.array([[0, 0], [1, 1], [2, 2], [3, 3]])
    times = np.array([0.1, 0.0, 0.1, 0.0])  # frame 0: beams 1 and 3; frame 1: beams 0 and 2
    scan = LidarScan(np.ones(4), np.ones(4, bool), np.zeros((4, 3)), np.ones(4), np.arange(4),
                     0.2, 2, times=times)  # fmt: skip
    acq = Acquisition(planned, np.arange(4.0), (4, 4), detail=scan, planned=planned)
    np.testing.assert_array_equal(beam_table(acq)[:, 0], [1, 3, 0, 2])


class _Paced(_Timed):
    """The stand-in with a tour-like time: 1 ms per sample + 0.1 ms per pixel of path in the
    planner's row-major order, and a micromirror-like receiver for the receiver fit."""

    class options:  # the attribute the receiver fit reads
        receiver_px = (8, 8)

    def scan_seconds(self, rc):
        rc = np.asarray(rc, float)
        o = np.lexsort((rc[:, 1], rc[:, 0]))
        path = np.abs(np.diff(rc[o], axis=0)).max(axis=1).sum() if len(rc) > 1 else 0.0
        return 1e-3 * len(rc) + 1e-4 * path

    def acquire(self, rc, *, rng=None):
        acq = super().acquire(rc, rng=rng)
        return Acquisition(acq.rc, acq.values, acq.shape, frames=len(rc),
                           seconds=self.scan_seconds(rc))  # fmt: skip


def test_a_scan_time_fit_scans_within_its_reference_s_time():
    from simlunar.study.lidar_planners import SensorFit

    image, depth = _guide()
    o = LidarStudyOptions(
        planners=("grid", "wavelet_lloyd"),
        strategies={"wavelet_lloyd": "wavelet"},
        planner_opts={"wavelet_lloyd": {"placement": "lloyd"}},
        fits={"wavelet_lloyd": SensorFit("scan_time", "grid")},
        densities=(1 / 16, 1 / 64),
        trials=1,
    )
    rows = run_lidar_study(_scene(), (image, depth), o, rng=0, sensor=_Paced(depth)).rows
    sec = {(r["planner"], r["k"]): (r["seconds"], r["samples"]) for r in rows}
    for k in (16, 64):
        assert sec[("wavelet_lloyd", k)][0] <= sec[("grid", k)][0] + 1e-12
        # the budget is used: near the reference's time (one more sample would exceed it)
        assert sec[("wavelet_lloyd", k)][0] > 0.8 * sec[("grid", k)][0]


def test_a_receiver_fit_keeps_one_dot_per_receiver_pixel():
    from simlunar.lidar.planning import receiver_cells
    from simlunar.study.lidar_planners import SensorFit

    image, depth = _guide()
    seen = []

    class _Rx(_Paced):
        def acquire(self, rc, *, rng=None):
            seen.append(np.asarray(rc))
            return super().acquire(rc, rng=rng)

    o = LidarStudyOptions(
        sensor="micromirror_flash",
        planners=("wavelet",),
        fits={"wavelet": SensorFit("receiver")},
        densities=(1 / 16,),
        trials=2,
    )
    run_lidar_study(_scene(), (image, depth), o, rng=0, sensor=_Rx(depth))
    assert len(seen) == 2
    for rc in seen:
        assert len(rc) == 64
        assert np.bincount(receiver_cells(rc, (32, 32), (8, 8)), minlength=64).max() == 1


def test_a_receiver_fit_keeps_a_lloyd_layout_and_moves_only_the_dots_over_the_cap():
    # a Lloyd-placed label under a receiver fit: the sensor gets the planner's own layout
    # moved under the cap (receiver_capped_layout), not a redraw inside receiver pixels
    from simlunar.lidar.planning import receiver_capped_layout, receiver_cells
    from simlunar.study.lidar_planners import SensorFit

    image, depth = _guide()
    seen = []

    class _Rx(_Paced):
        def acquire(self, rc, *, rng=None):
            seen.append(np.asarray(rc))
            return super().acquire(rc, rng=rng)

    def study(fits):
        seen.clear()
        o = LidarStudyOptions(sensor="micromirror_flash", planners=("lloyd_uniform",),
                              fits=fits, densities=(1 / 16,), trials=1)  # fmt: skip
        run_lidar_study(_scene(), (image, depth), o, rng=0, sensor=_Rx(depth))
        return seen[0]

    free = study({})
    capped = study({"lloyd_uniform": SensorFit("receiver")})
    assert np.bincount(receiver_cells(capped, (32, 32), (8, 8)), minlength=64).max() == 1
    expect = receiver_capped_layout(free, shape=(32, 32), receiver_shape=(8, 8))
    np.testing.assert_array_equal(capped, expect)
    # and the layout is the planner's: the dots within the cap did not move
    cell = receiver_cells(free, (32, 32), (8, 8))
    alone = np.bincount(cell, minlength=64)[cell] == 1
    np.testing.assert_array_equal(capped[alone], free[alone])
    assert alone.sum() > len(free) // 2


def test_the_learned_map_gets_its_density(monkeypatch):
    # the learned map is predicted per sample density: the LIDAR study asks it once per k
    import simlunar.study.sampling_planners as sp

    asked = []

    def weights(base, image, *, feature_opts=None, coefficients=None):
        asked.append((base, (feature_opts or {}).get("density")))
        return np.ones(image.shape[:2])

    monkeypatch.setattr(sp, "strategy_weights", weights)
    image, depth = _guide()
    o = LidarStudyOptions(planners=("learned",), densities=(1 / 16, 1 / 64), trials=1,
                          planner_opts={"learned": {"feature_opts": {"model": "m.joblib"}}})  # fmt: skip
    rows = run_lidar_study(_scene(), (image, depth), o, rng=0, sensor=_Timed(depth)).rows
    assert sorted(asked) == [("learned", 1 / 64), ("learned", 1 / 16)]
    assert {r["k"] for r in rows} == {16, 64}


def test_safe_site_rows_come_beside_the_hazard_scores():
    from simlunar.metrics.safe_site import SiteOptions

    image, depth = _guide()
    site = SiteOptions(semi_axes_m=(3.0, 3.0), pitch_m=6.0, window_px=5, baseline_px=1)
    o = LidarStudyOptions(planners=("grid",), densities=(1 / 4,), trials=1, safe_site=site,
                          hazard=HazardOptions())  # fmt: skip
    rows = run_lidar_study(_scene(), (image, depth), o, rng=0, sensor=_Timed(depth)).rows
    got = {r["metric"]: r["value"] for r in rows}
    assert {"safe_site", "safe_site_precision", "safe_sites_available"} <= set(got)
    assert got["safe_site"] in (0.0, 1.0) and 0.0 <= got["safe_sites_available"] <= 1.0


def test_landing_rows_name_every_hazard_size():
    from simlunar.metrics.landing import LandingOptions, landing_metric_names

    image, depth = _guide()
    land = LandingOptions(rock_heights_m=(0.15, 0.3), footprint_m=2.0, site_radius_m=2.0,
                          site_pitch_m=4.0)  # fmt: skip
    o = LidarStudyOptions(planners=("grid",), densities=(1 / 4,), trials=1, landing=land)
    rows = run_lidar_study(_scene(), (image, depth), o, rng=0, sensor=_Timed(depth)).rows
    got = {r["metric"]: r["value"] for r in rows}
    assert set(landing_metric_names(land)) <= set(got)
    assert {"hazard_recall_rock_15cm", "hazard_recall_rock_30cm", "hazard_recall_slope_5deg",
            "false_safe_site", "height_rms", "slope_rms_deg"} <= set(got)  # fmt: skip
    assert got["false_safe_site"] in (0.0, 1.0) and got["height_rms"] >= 0.0
