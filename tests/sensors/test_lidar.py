"""The LIDAR sensors through the Sensor protocol on a plane: depths at the planned pixels,
cost from the steering / pulse-rate model, plan-directed flash revisits."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar import (
    DetectorOptions,
    FootprintOptions,
    PulseOptions,
    SteeringOptions,
    pointing_angles,
    scan_timing,
)
from simlunar.terrain import Terrain

H = 50.0
DET = DetectorOptions(signal_photons=2e6, background_photons_per_s=0.0, pulses=4)


def _plane(size: float = 80.0) -> Terrain:
    n = int(size)
    return Terrain(
        heights=np.zeros((n, n)),
        albedo=np.full((n, n), 0.2, np.float32),
        spacing=1.0,
        origin=(-size / 2, size / 2),
    )


def _camera(px: int, fov_deg: float) -> Camera:
    pose = Pose.look_at([0.0, 0.0, H], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    return Camera(Intrinsics.from_fov(px, px, fov_deg), pose)


def test_revisit_tiles_pick_the_most_planned_subfields():
    from simlunar.sensors.lidar import revisit_tiles

    rc = np.array([[1, 1], [2, 2], [3, 1], [10, 12], [11, 13], [15, 0]])
    # 16 x 16 guide, zoom 2: tile (0, 0) has 3, (1, 1) 2, (1, 0) 1
    assert revisit_tiles(rc, (16, 16), 2, 2).tolist() == [[0, 0], [1, 1]]


def test_tile_camera_sees_one_tile_of_the_guide_field():
    from simlunar.sensors.lidar import tile_camera

    guide = _camera(32, 20.0)
    cam = tile_camera(guide, (1, 0), 4, (8, 8))
    # the tile's corners (guide u in [0, 8], v in [8, 16]) map to the receiver's corners
    _, d = guide.rays(np.array([[0.0, 8.0], [8.0, 16.0], [4.0, 12.0]]))
    uv, _ = cam.project(guide.position + 30.0 * d)
    assert uv == pytest.approx(np.array([[0.0, 0.0], [8.0, 8.0], [4.0, 4.0]]))


def test_receiver_samples_snap_to_the_guide_lattice():
    from simlunar.lidar.returns import LidarScan
    from simlunar.sensors.lidar import _to_guide

    guide = _camera(32, 20.0)
    # receiver pixel centres of an 8 x 8 receiver: guide (u, v) = 4 j + 2, up to float rounding
    uv = np.array([[2.0, 2.0], [6.0, 30.0]]) * (1 + 1e-14)
    o, d = guide.rays(uv)
    pts = o + 40.0 * d
    scan = LidarScan(np.full(2, 40.0), np.ones(2, bool), pts, np.ones(2), np.arange(2), 0.1, 1)
    acq = _to_guide(scan, guide)
    # exact lattice coordinates: nearly co-circular float points give sliver triangles
    assert acq.rc.tolist() == [[1.5, 1.5], [29.5, 5.5]]


def test_flash_options_refuse_more_revisits_than_tiles():
    from simlunar.sensors.lidar import FlashLidarOptions

    with pytest.raises(ValueError, match="tiles"):
        FlashLidarOptions(revisits=5, zoom=2)
    with pytest.raises(ValueError, match="zoom must be >= 2, got 1"):
        FlashLidarOptions(zoom=1)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"revisits": -1}, "revisits must be >= 0, got -1"),
        ({"revisit_from": "image"}, "revisit_from must be one of 'plan', 'ranges', 'both'"),
        ({"range_weight": 1.5}, r"range_weight must be <= 1, got 1\.5"),
        ({"repoint_s": float("inf")}, "repoint_s must be a finite number, got inf"),
        ({"receiver_px": (64, 0)}, r"receiver_px must be each >= 1, got \(64, 0\)"),
        ({"receiver_px": (64,)}, r"receiver_px must be \(rows, cols\) >= 1"),
    ],
)
def test_flash_options_refuse_bad_values(kw, match):
    from simlunar.sensors.lidar import FlashLidarOptions

    with pytest.raises(ValueError, match=match):
        FlashLidarOptions(**kw)


def test_a_lidar_needs_a_perspective_guide_camera():
    from simlunar.geometry import OrthoCamera
    from simlunar.sensors.lidar import LidarScene

    ortho = OrthoCamera.nadir_for_grid((8, 8), 1.0, (0.0, 8.0), altitude=10.0)
    with pytest.raises(ValueError, match="perspective"):
        LidarScene(_plane(), ortho)


def test_registry_names_the_lidar_sensors():
    from simlunar.sensors import SENSORS

    assert {"steered_beam", "flash", "micromirror_flash"} <= set(SENSORS)
    for name in ("steered_beam", "flash", "micromirror_flash"):
        cls, opts = SENSORS[name]
        assert cls.name == name and opts() is not None


@pytest.mark.render
def test_steered_beam_ranges_the_planned_pixels(mi):
    from simlunar.lidar.scan import SteeredBeamOptions, guide_directions
    from simlunar.sensors import LidarScene, SteeredBeam

    steer = SteeringOptions(1.0, 10.0, 1e-3, 1000.0, 4)
    opts = SteeredBeamOptions(
        footprint=FootprintOptions(5e-4, samples=8),
        pulse=PulseOptions(fwhm_s=1e-9),
        detector=DET,
        steering=steer,
        window_m=4.0,
        margin_m=1.0,
        batch=32,
    )
    cam = _camera(32, 40.0)
    sensor = SteeredBeam(LidarScene(_plane(), cam), opts)
    assert sensor.needs_plan
    rc = np.random.default_rng(0).integers(0, 32, (40, 2))
    acq = sensor.acquire(rc, rng=1)
    assert acq.rc.tolist() == rc.tolist() and acq.shape == (32, 32)
    assert acq.values == pytest.approx(H, abs=opts.bin_range_m)  # z-depth of z = 0 from 50 m
    ang = pointing_angles(guide_directions(cam, rc), cam.pose)
    order = acq.detail.order
    assert acq.seconds == pytest.approx(scan_timing(ang, order, options=steer).total_s)
    assert acq.seconds > 0 and acq.frames == 40 * 4
    with pytest.raises(ValueError, match="rc is required"):
        sensor.acquire(None, rng=0)


@pytest.mark.render
def test_a_steered_beam_fires_its_pulses_at_the_instrument_s_energy(mi):
    # LOLA's 0.54 mJ per beam: 40 points x 4 pulses per point = 160 pulses, 86.4 mJ, priced
    # before the scan (what a budget fit asks) and counted by it; with the expert photon
    # scales (no instrument) nothing is counted and no budget can be priced
    from simlunar.lidar.hardware import INSTRUMENTS
    from simlunar.lidar.scan import SteeredBeamOptions, with_hardware
    from simlunar.sensors import LidarScene, SteeredBeam

    base = SteeredBeamOptions(footprint=FootprintOptions(5e-4, samples=8), window_m=4.0,
                              margin_m=1.0, batch=32,
                              steering=SteeringOptions(1.0, 10.0, 1e-3, 1000.0, 4))  # fmt: skip
    opts = with_hardware(base, INSTRUMENTS["lola_beam"])
    scene = LidarScene(_plane(), _camera(32, 40.0))
    sensor = SteeredBeam(scene, opts)
    rc = np.random.default_rng(0).integers(0, 32, (40, 2))
    assert opts.steering.pulses_per_point == 4
    assert sensor.scan_energy_j(rc) == pytest.approx(160 * 0.54e-3)
    acq = sensor.acquire(rc, rng=1)
    assert acq.frames == 160 and acq.energy_j == pytest.approx(160 * 0.54e-3)
    expert = SteeredBeam(scene, dataclasses.replace(base, detector=DET))
    assert expert.acquire(rc, rng=1).energy_j == 0.0
    with pytest.raises(ValueError, match="an energy budget needs the steered_beam's pulse"):
        expert.scan_energy_j(rc)


@pytest.mark.render
def test_flash_lidar_with_and_without_revisits(mi):
    from simlunar.lidar.flash import FlashOptions
    from simlunar.render.transient import TransientOptions
    from simlunar.sensors import FlashLidar, FlashLidarOptions, LidarScene

    flash = FlashOptions(
        detector=DET,
        pulse=PulseOptions(fwhm_s=1e-9),
        transient=TransientOptions(spp=8),
        pulse_rate_hz=20.0,
    )
    scene = LidarScene(_plane(), _camera(32, 8.0))
    plain = FlashLidar(scene, FlashLidarOptions(flash, receiver_px=(8, 8)))
    assert not plain.needs_plan
    acq = plain.acquire(None, rng=0)
    assert len(acq.values) == 64 and acq.frames == 1
    assert acq.seconds == pytest.approx(4 / 20.0)
    assert acq.values == pytest.approx(H, abs=flash.bin_range_m)
    # receiver pixel (0, 0) of 8 x 8 on a 32 x 32 guide: centre at guide (row, col) (1.5, 1.5)
    assert acq.rc[0] == pytest.approx([1.5, 1.5])

    directed = FlashLidar(scene, FlashLidarOptions(flash, receiver_px=(8, 8), revisits=1, zoom=2))
    rc = np.array([[20, 3], [25, 10], [30, 14], [2, 30]])  # most in tile (1, 0)
    acq = directed.acquire(rc, rng=0)
    assert acq.frames == 2 and acq.seconds == pytest.approx(2 * 4 / 20.0)
    assert acq.values == pytest.approx(H, abs=flash.bin_range_m)
    in_tile = (acq.rc[:, 0] >= 16) & (acq.rc[:, 1] < 16)
    # the revisit's 64 samples replace the full frame's 16 in that quarter of the field
    assert in_tile.sum() == 64 and len(acq.values) == 48 + 64
    directed.acquire(rc, rng=1)
    assert len(directed._frames) == 2  # frames rendered once, read with fresh noise


@pytest.mark.render
def test_flash_revisits_from_the_first_frame_s_ranges_and_their_repointing_time(mi):
    # a 1 m box on the plane in one quarter of the field; the plan points at another quarter.
    # Revisits from the ranges go to the box's quarter (the first frame's own points are
    # rough there), from the plan to the plan's; each revisit costs the re-pointing time too
    from simlunar.lidar.flash import FlashOptions
    from simlunar.render.transient import TransientOptions
    from simlunar.sensors import FlashLidar, FlashLidarOptions, LidarScene

    t = _plane()
    h = t.heights.copy()
    h[36:39, 41:44] = 1.0  # world x in (1, 4), y in (1, 4)
    terrain = Terrain(h, t.albedo, t.spacing, t.origin)
    cam = _camera(32, 8.0)
    uv, _ = cam.project(np.array([[2.5, 2.5, 1.0]]))
    box_tile = [int(uv[0, 1] * 2 // 32), int(uv[0, 0] * 2 // 32)]
    other = [1 - box_tile[0], 1 - box_tile[1]]
    rc = np.array([[other[0] * 16 + 8, other[1] * 16 + 8]] * 4)
    flash = FlashOptions(detector=DET, pulse=PulseOptions(fwhm_s=1e-9),
                         transient=TransientOptions(spp=8), pulse_rate_hz=20.0)  # fmt: skip
    scene = LidarScene(terrain, cam)
    for source, tile in (("ranges", box_tile), ("plan", other)):
        o = FlashLidarOptions(flash, receiver_px=(8, 8), revisits=1, zoom=2,
                              revisit_from=source, repoint_s=0.05)  # fmt: skip
        sensor = FlashLidar(scene, o)
        assert sensor.needs_plan == (source != "ranges")
        acq = sensor.acquire(None if source == "ranges" else rc, rng=0)
        assert acq.seconds == pytest.approx(2 * 4 / 20.0 + 0.05)
        ti = (acq.rc[:, 0] // 16).astype(int) * 2 + (acq.rc[:, 1] // 16).astype(int)
        assert np.bincount(ti, minlength=4)[tile[0] * 2 + tile[1]] == 64  # the revisit's


def _beam_options():
    from simlunar.lidar.scan import SteeredBeamOptions

    return SteeredBeamOptions(
        footprint=FootprintOptions(5e-4, samples=8),
        pulse=PulseOptions(fwhm_s=1e-9),
        detector=DET,
        steering=SteeringOptions(1.0, 10.0, 1e-3, 1000.0, 4),
        window_m=4.0,
        margin_m=1.0,
        batch=32,
    )


def test_repointing_is_the_move_and_settle_of_a_two_point_tour(mi):
    from simlunar.sensors import LidarScene, SteeredBeam

    sensor = SteeredBeam(LidarScene(_plane(), _camera(32, 40.0)), _beam_options())
    a, b = np.array([3, 4]), np.array([28, 20])
    one = sensor.scan_seconds(a[None])  # one dwell, no move
    # a tour of a and b: one dwell each plus the move a -> b and its settle
    assert sensor.repoint_seconds(a, b) == pytest.approx(
        sensor.scan_seconds(np.stack([a, b])) - 2 * one
    )
    assert sensor.repoint_seconds(b, a) == pytest.approx(sensor.repoint_seconds(a, b))
    assert sensor.repoint_seconds(a, a) == 0.0


def test_a_multi_round_steered_beam_ranges_every_round_and_adds_up_their_time(mi):
    from simlunar.planner import SequentialOptions
    from simlunar.sensors import LidarScene, SteeredBeam
    from simlunar.study.lidar_planners import LidarRounds

    sensor = SteeredBeam(LidarScene(_plane(), _camera(32, 40.0)), _beam_options())
    scans = []
    acquire = sensor.acquire
    sensor.acquire = lambda rc, rng=None: scans.append(acquire(rc, rng=rng)) or scans[-1]
    rounds = LidarRounds(SequentialOptions(max_rounds=3, first_share=0.5, batch_share=0.3),
                         None, (32, 32))  # fmt: skip
    acq, n = rounds.acquire(40, sensor, 1, 2)
    assert n == len(scans) == 3 and len(acq.values) == 40
    assert acq.values == pytest.approx(H, abs=0.05)  # z-depth of the plane from 50 m
    gaps = [
        sensor.repoint_seconds(a.planned[a.detail.order[-1]], b.planned[b.detail.order[0]])
        for a, b in itertools.pairwise(scans)
    ]
    assert min(gaps) > 0
    assert acq.seconds == pytest.approx(sum(s.seconds for s in scans) + sum(gaps))
    assert acq.frames == sum(s.frames for s in scans) == 40 * 4


@pytest.mark.render
def test_a_descending_steered_beam_s_rounds_continue_its_trajectory(mi):
    # multi-round planning while descending at 2 m/s and drifting 1 m/s east over the z = 0
    # plane from 50 m (a slow gimbal: rounds of seconds, the platform falls metres). Round r starts when round r - 1 ended plus the re-pointing from its
    # last beam to round r's first (not at t = 0), so each beam leaves from where the platform
    # is at (round start + its time in the round). With the pose known exactly ("exact")
    # every round's points lie on the plane (z-depth 50 m in the guide view); placed from
    # the pose at t = 0 ("start") each point sits 2 m/s x its firing time above the plane:
    # the trajectory's altitude at that time, hand-checkable at each round's first beam
    from simlunar.lidar.trajectory import Navigation, PlatformMotion
    from simlunar.planner import SequentialOptions
    from simlunar.sensors import LidarScene, SteeredBeam
    from simlunar.study.lidar_planners import LidarRounds

    sensor = SteeredBeam(LidarScene(_plane(), _camera(32, 40.0)), _beam_options())
    plan = LidarRounds(SequentialOptions(max_rounds=3, first_share=0.5, batch_share=0.3),
                       None, (32, 32))  # fmt: skip

    class Kept:  # the sensor's rounds of one acquisition, with the cells each was asked
        def __init__(self, rounds):
            self.rounds, self.asked, self.scans = rounds, [], []

        @property
        def gaps_s(self):
            return self.rounds.gaps_s

        def __call__(self, rc):
            self.asked.append(np.asarray(rc))
            self.scans.append(self.rounds(rc))
            return self.scans[-1]

    def run(compensation):
        motion = PlatformMotion((1.0, 0.0, -2.0), navigation=Navigation(compensation))
        sensor.options = dataclasses.replace(sensor.options, motion=motion)
        kept = []
        sensor.rounds = lambda rng=None: (
            kept.append(Kept(SteeredBeam.rounds(sensor, rng=rng))) or kept[0]
        )
        acq, n = plan.acquire(40, sensor, 1, 2)
        del sensor.rounds
        return acq, n, kept[0].rounds, kept[0]

    acq, n, br, k = run("exact")
    scans = k.scans
    assert n == len(scans) == 3 and len(acq.values) > 0.9 * 40
    # each round starts at the previous round's end plus the re-pointing from its last beam
    # to the next round's first (visiting order)
    for r in (1, 2):
        a, b = scans[r - 1], scans[r]
        gap = sensor.repoint_seconds(k.asked[r - 1][a.detail.order[-1]],
                                     k.asked[r][b.detail.order[0]])  # fmt: skip
        assert br.gaps_s[r - 1] == gap > 0
        assert br.starts_s[r] == pytest.approx(br.starts_s[r - 1] + a.seconds + gap)
    assert br.starts_s[0] == 0.0
    assert acq.seconds == pytest.approx(br.starts_s[-1] + scans[-1].seconds)
    # every round's points on the plane (photon noise: within 5 cm, one time bin)
    pts = acq.detail.points[acq.detail.valid]
    assert pts[:, 2] == pytest.approx(0.0, abs=0.05)
    assert acq.values == pytest.approx(H, abs=0.05)
    # the joined scan's times are the trajectory's: round r's from its start
    sizes = np.cumsum([0] + [len(s.detail.valid) for s in scans])
    for r, s in enumerate(scans):
        np.testing.assert_allclose(acq.detail.times[sizes[r]:sizes[r + 1]],
                                   br.starts_s[r] + s.detail.times)  # fmt: skip
    _, _, br, k = run("start")
    scans = k.scans
    assert br.starts_s[1] > scans[0].seconds
    for r, s in enumerate(scans):
        t = br.starts_s[r] + s.detail.times  # when each beam fired on the trajectory
        v = s.detail.valid
        assert s.detail.points[v, 2] == pytest.approx(2.0 * t[v], abs=0.05)
        first = s.detail.order[0]  # fired when the round starts
        assert s.detail.times[first] == 0.0 and v[first]
        assert s.detail.points[first, 2] == pytest.approx(2.0 * br.starts_s[r], abs=0.05)


@pytest.mark.render
def test_a_descending_flash_takes_each_frame_from_its_own_pose(mi):
    # 10 m/s descent over the z = 0 plane; the full frame at t = 0 from 50 m, the revisit
    # after one frame (0.2 s) and its re-pointing (0.3 s): at t = 0.5 s, from 45 m.
    # Navigation "exact" places every point on the plane; "start" (the pose at t = 0 for all)
    # lifts the revisit's points by the 5 m the platform came down, the full frame's by none
    from simlunar.lidar.flash import FlashOptions
    from simlunar.lidar.trajectory import Navigation, PlatformMotion
    from simlunar.render.transient import TransientOptions
    from simlunar.sensors import FlashLidar, FlashLidarOptions, LidarScene

    flash = FlashOptions(detector=DET, pulse=PulseOptions(fwhm_s=1e-9),
                         transient=TransientOptions(spp=8), pulse_rate_hz=20.0)  # fmt: skip
    scene = LidarScene(_plane(), _camera(32, 8.0))
    rc = np.array([[20, 3], [25, 10], [30, 14]])  # tile (1, 0) of a 2 x 2 zoom

    def run(compensation):
        motion = PlatformMotion((0.0, 0.0, -10.0), navigation=Navigation(compensation))
        opts = FlashLidarOptions(flash, receiver_px=(8, 8), revisits=1, zoom=2, repoint_s=0.3,
                                 motion=motion)  # fmt: skip
        acq = FlashLidar(scene, opts).acquire(rc, rng=0)
        pts = acq.detail.points[acq.detail.valid]
        revisit = np.arange(len(acq.detail.valid))[acq.detail.valid] >= 48  # after the full frame
        return acq, pts, revisit

    acq, pts, revisit = run("exact")
    assert acq.frames == 2 and acq.seconds == pytest.approx(2 * 0.2 + 0.3)
    assert pts[:, 2] == pytest.approx(0.0, abs=flash.bin_range_m)
    assert acq.values == pytest.approx(H, abs=flash.bin_range_m)
    _, pts, revisit = run("start")
    assert revisit.sum() == 64
    assert pts[~revisit, 2] == pytest.approx(0.0, abs=flash.bin_range_m)
    assert pts[revisit, 2] == pytest.approx(5.0, abs=flash.bin_range_m)
