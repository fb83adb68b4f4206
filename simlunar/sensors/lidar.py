"""Time-of-flight range sensors: steered beam, flash LIDAR and micromirror-steered flash.

Each wraps an acquisition of :mod:`simlunar.lidar.scan` / :mod:`simlunar.lidar.flash` (rendered by
:mod:`simlunar.render.beam_capture` / :mod:`simlunar.render.flash_lidar`) behind the
:class:`~simlunar.sensors.base.Sensor` protocol. A sensor is bound to a scene (terrain, BSDF,
sun) and to the guide camera; its ranges become z-depths in the guide view
(:meth:`~simlunar.lidar.returns.LidarScan.depth`) at the guide (row, col) index coordinates
where each measured point projects, and its cost is the modelled acquisition time.

- :class:`SteeredBeam`: one beam visits the planned pixels' directions from the guide camera's
  centre, in the order of :func:`simlunar.lidar.order_scan`; seconds from the steering
  mechanics (:func:`simlunar.lidar.scan_timing`). The rounds of a multi-round plan
  (:class:`~simlunar.sensors.rounds.PlatformRounds`) continue a moving platform's trajectory
  one after the other.
- :class:`FlashLidar`: a low-resolution receiver co-boresighted with the guide camera takes one
  full-field frame; with ``revisits`` > 0 the planned pixels direct that many zoomed frames at
  the sub-fields (tiles of ``1 / zoom`` of the field) holding most planned pixels, whose finer
  samples replace the full-field ones there. Seconds: frames x pulses / pulse rate. On a moving
  platform (``FlashLidarOptions.motion``) each frame is taken from the pose at its time.
- :class:`~simlunar.sensors.micromirror.MicromirrorFlash` (its own module): a micromirror projector at the guide camera lights only the
  planned pixels; a small receiver times them (dots sharing a receiver pixel go to different
  frames). On a moving platform (``MicromirrorOptions.motion``) each frame is rendered from the
  pose at its time and its dots are scored where their points project in the guide view.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Camera, Intrinsics
from simlunar.lidar import order_scan, pointing_angles, scan_timing
from simlunar.lidar.flash import FlashOptions, flash_window, read_flash
from simlunar.lidar.join import concat_scans, flat_scan, subset_scan
from simlunar.lidar.planning import choose_tiles, tile_range_scores
from simlunar.lidar.returns import LidarScan, fired_energy_j
from simlunar.lidar.scan import (
    SteeredBeamOptions,
    guide_directions,
    steered_beam_scan,
    visiting_order,
)
from simlunar.lidar.trajectory import Flight, PlatformMotion, camera_at, place_points, rotate_small
from simlunar.registry import Options, option, shared_option
from simlunar.render.beam_capture import beam_capture
from simlunar.render.transient import flash_frame
from simlunar.sensors.base import Acquisition, NothingMeasured
from simlunar.sensors.rounds import PlatformRounds, platform_trajectory

__all__ = [
    "FLASH_SENSOR_OPTIONS",
    "FlashLidar",
    "FlashLidarOptions",
    "LidarScene",
    "SteeredBeam",
    "check_receiver_px",
    "revisit_tiles",
    "tile_camera",
]


@dataclass(frozen=True, eq=False)
class LidarScene:
    """What a LIDAR measures: terrain, guide camera (the sensor's origin and boresight),
    BSDF spec and sun (rendered as background).

    Attributes
    ----------
    terrain : Terrain
    camera : geometry.Camera
        Perspective pinhole guide camera (square pixels); the sensor sits at its centre.
    bsdf : BSDF spec or None (Lambert)
    sun : SunLight or None
    """

    terrain: object
    camera: Camera
    bsdf: object = None
    sun: object = None

    def __post_init__(self):
        if not isinstance(self.camera, Camera) or self.camera.aperture_radius > 0:
            raise ValueError(
                "a LIDAR needs a perspective pinhole guide camera (the sensor sits at its "
                f"centre), got {type(self.camera).__name__}"
            )


def _need_hardware(options, name: str) -> None:
    """An energy budget needs the pulse energy, which only an instrument's hardware names."""
    if getattr(options, "hardware", None) is None:
        raise ValueError(
            f"an energy budget needs the {name}'s pulse energy: give an instrument or hardware "
            "(the expert photon scales have none)"
        )


def _to_guide(scan: LidarScan, camera: Camera, rc=None, *, detail=None, **cost) -> Acquisition:
    """The valid points of a scan as guide-view (row, col) and z-depth: at the planned ``rc``
    (one per sample of ``scan``) or, without a plan, where each point projects; its cost
    (``frames``, ``seconds``, ``energy_j``) the scan's unless ``cost`` gives it."""
    cost = {"frames": scan.frames, "seconds": scan.seconds, "energy_j": scan.energy_j, **cost}
    valid = np.asarray(scan.valid).ravel()
    if not valid.any():
        raise NothingMeasured("the LIDAR detected no return")
    pts = scan.points.reshape(-1, 3)[valid]
    uv, z = camera.project(pts)
    if rc is None:
        # receiver pixel centres land on lattices of the guide grid up to rounding (1e-13);
        # snapped, they are exact lattices, whose Delaunay triangles are well shaped (nearly
        # co-circular float points gave sliver triangles that the rasteriser extrapolated)
        rc = np.round(np.stack([uv[:, 1] - 0.5, uv[:, 0] - 0.5], axis=-1), 6)
        planned = None
    else:
        planned = np.asarray(rc).reshape(-1, 2)
        rc = planned[valid]
    detail = scan if detail is None else detail
    return Acquisition(rc, z, camera.shape, detail=detail, planned=planned, **cost)


class SteeredBeam:
    """A gimbaled altimeter / galvanometer scanner at the guide camera's centre.

    The beam capture (terrain, origin, sun) is built once and reused by every plan; the gimbal's
    zero is the guide camera's boresight.

    Parameters
    ----------
    scene : LidarScene
    options : SteeredBeamOptions, optional
    """

    name = "steered_beam"
    needs_plan = True

    def __init__(self, scene: LidarScene, options: SteeredBeamOptions | None = None) -> None:
        self.scene = scene
        o = options or SteeredBeamOptions()
        if o.steering.model == "continuous_raster" and o.steering.line_pitch_rad is None:
            # one line per guide pixel row at the boresight
            pitch = 1.0 / scene.camera.intrinsics.fy
            o = dataclasses.replace(
                o, steering=dataclasses.replace(o.steering, line_pitch_rad=pitch)
            )
        self.options = o
        self.capture = beam_capture(
            scene.terrain,
            scene.camera.position,
            options=self.options,
            sun=scene.sun,
            bsdf=scene.bsdf,
        )

    def acquire(self, rc: np.ndarray | None, *, rng=None) -> Acquisition:
        """Range the planned guide pixels ``rc`` ((k, 2) int (row, col)); ``rng``: photon noise."""
        if rc is None:
            raise ValueError("a steered beam ranges planned pixels: rc is required")
        cam, m = self.scene.camera, self.options.motion
        if m is None:
            d = guide_directions(cam, rc)
            scan = steered_beam_scan(self.capture, d, options=self.options, rng=rng,
                                     boresight=cam.pose)  # fmt: skip
            return _to_guide(scan, cam, rc)
        g = np.random.default_rng(rng)
        return self._moving(rc, g, self.trajectory(g), 0.0)

    def trajectory(self, rng):
        """The platform's trajectory from the guide camera's centre at t = 0 (its jitter
        phases drawn from ``rng``, a Generator); None at rest."""
        return platform_trajectory(self.scene.camera, self.options.motion, rng)

    def _moving(self, rc, rng, trajectory, start_s: float) -> Acquisition:
        """The acquisition of ``rc`` on ``trajectory`` from ``start_s`` (s on it)."""
        cam, m = self.scene.camera, self.options.motion
        flight = Flight(trajectory, m.navigation, start_s, m.retarget)
        scan = steered_beam_scan(self.capture, guide_directions(cam, rc), options=self.options,
                                 rng=rng, boresight=cam.pose, flight=flight)  # fmt: skip
        # a moving beam measures where its points project, not the planned pixels exactly
        return _to_guide(scan, cam, None)

    def rounds(self, *, rng=None) -> PlatformRounds:
        """The rounds of one multi-round acquisition, measured one after the other
        (:class:`~simlunar.sensors.rounds.PlatformRounds`; photon noise and the trajectory's
        jitter from ``rng``)."""
        return PlatformRounds(self, rng)

    def round_gap_seconds(self, last_rc, rc) -> float:
        """Re-pointing (s) between two rounds: from guide pixel ``last_rc`` ((2,), the last
        beam of a round) to the first beam the next round ``rc`` ((m, 2)) visits
        (:func:`~simlunar.lidar.scan.visiting_order`)."""
        cam = self.scene.camera
        rc = np.asarray(rc).reshape(-1, 2)
        _, order = visiting_order(guide_directions(cam, rc), boresight=cam.pose,
                                  options=self.options)  # fmt: skip
        return self.repoint_seconds(last_rc, rc[order[0]])

    def scan_seconds(self, rc: np.ndarray) -> float:
        """Modelled time (s) of scanning guide pixels ``rc`` (k, 2) (the steering mechanics
        and the visiting order; no render, no measurement: what a planner may ask)."""
        cam, o = self.scene.camera, self.options
        angles = pointing_angles(guide_directions(cam, rc), cam.pose)
        order = order_scan(angles, steering=o.steering, options=o.order)
        return float(scan_timing(angles, order, options=o.steering).total_s)

    def scan_energy_j(self, rc: np.ndarray) -> float:
        """Modelled laser energy (J) of scanning guide pixels ``rc`` (k, 2): ``k`` x pulses per
        point x the hardware's pulse energy (an altimeter's gate steps not counted: what a
        planner may ask before the scan)."""
        o = self.options
        _need_hardware(o, self.name)
        return fired_energy_j(o, len(rc) * int(o.steering.pulses_per_point))

    def repoint_seconds(self, from_rc, to_rc) -> float:
        """Modelled time (s) of re-pointing the beam from guide pixel ``from_rc`` to ``to_rc``
        ((2,) (row, col)) between two scans: the move and its settle (no dwell), as
        :func:`~simlunar.lidar.scan_timing` prices every move of a tour."""
        cam, o = self.scene.camera, self.options
        rc = np.asarray([from_rc, to_rc], float).reshape(2, 2)
        a = pointing_angles(guide_directions(cam, rc), cam.pose)
        t = scan_timing(a[1:], options=o.steering, start=a[0])
        return float(t.move_s + t.settle_s)


#: the options that :class:`FlashLidarOptions` and
#: :class:`~simlunar.sensors.micromirror.MicromirrorOptions` declare alike: name -> keywords of
#: :func:`simlunar.registry.option` (for :func:`simlunar.registry.shared_option`)
FLASH_SENSOR_OPTIONS: dict[str, dict] = {
    "flash": dict(
        default=dataclasses.MISSING,
        default_factory=FlashOptions,
        doc="pulse, detector (its pulses per frame), ranging, rendering, pulse rate",
    ),
    "receiver_px": dict(
        default=(64, 64),
        doc="the receiver array (rows, cols), each 1 .. 8192, with the guide camera's field of "
        "view",
        ge=1,
        le=8192,
    ),
    "motion": dict(
        default=None,
        doc="the platform's motion (simlunar.lidar.trajectory; None: at rest): each frame is "
        "taken from the pose at its own time and its points are placed with the sensor's "
        "navigation",
    ),
}


def check_receiver_px(receiver_px) -> None:
    """``ValueError`` unless ``receiver_px`` is (rows, cols), each >= 1."""
    if len(receiver_px) != 2 or min(receiver_px) < 1:
        raise ValueError(f"receiver_px must be (rows, cols) >= 1, got {receiver_px}")


@dataclass(frozen=True)
class FlashLidarOptions(Options):
    """Options of :class:`FlashLidar`.

    On a moving platform (``motion``) frame ``i`` is taken at ``i`` x (frame time +
    ``repoint_s``).
    """

    flash: FlashOptions = shared_option(FLASH_SENSOR_OPTIONS, "flash")
    receiver_px: tuple[int, int] = shared_option(FLASH_SENSOR_OPTIONS, "receiver_px")
    revisits: int = option(
        0,
        doc="zoomed frames directed by the plan after the full-field frame (0: no plan; at most "
        "zoom^2 and 64)",
        ge=0,
        le=64,
    )
    zoom: int = option(
        4,
        doc="a revisit frame sees 1 / zoom of the field on each axis (tiles of a zoom x zoom "
        "grid; 2 .. 16)",
        ge=2,
        le=16,
    )
    revisit_from: str = option(
        "plan",
        doc="what directs the revisits: the tiles holding most planned pixels (the image), the "
        "tiles whose first-frame ranges are roughest (simlunar.lidar.planning.tile_range_scores: "
        "the sensor's own measurement), or range_weight of the ranges' share plus the rest of "
        "the plan's (simlunar.lidar.planning.choose_tiles)",
        choices=("plan", "ranges", "both"),
    )
    range_weight: float = option(0.5, doc="both: the ranges' share of a tile's score", ge=0, le=1)
    repoint_s: float = option(
        0.0,
        doc="time to re-point and re-zoom the receiver before each revisit, added per revisit "
        "(at most 1000 s)",
        unit="s",
        key_unit="ms",
        ge=0,
        le=1000.0,
    )
    motion: PlatformMotion | None = shared_option(FLASH_SENSOR_OPTIONS, "motion")

    def __post_init__(self):
        super().__post_init__()
        check_receiver_px(self.receiver_px)
        if int(self.revisits) > int(self.zoom) ** 2:
            raise ValueError(f"revisits {self.revisits} > the {self.zoom}^2 tiles of the field")


def _tile_counts(rc: np.ndarray, shape, zoom: int) -> np.ndarray:
    """Planned pixels per tile of a zoom x zoom grid over ``shape``, (zoom, zoom)."""
    h, w = shape
    rc = np.asarray(rc, float).reshape(-1, 2)
    ti = np.clip((rc[:, 0] * zoom // h).astype(int), 0, zoom - 1)
    tj = np.clip((rc[:, 1] * zoom // w).astype(int), 0, zoom - 1)
    return np.bincount(ti * zoom + tj, minlength=zoom * zoom).reshape(zoom, zoom)


def revisit_tiles(rc: np.ndarray, shape, zoom: int, count: int) -> np.ndarray:
    """The ``count`` tiles (of a zoom x zoom grid over ``shape``) holding most planned pixels.

    Returns (count, 2) int (tile row, tile col), most planned pixels first (ties: row-major).
    """
    h, w = shape
    rc = np.asarray(rc, float).reshape(-1, 2)
    ti = np.clip((rc[:, 0] * zoom // h).astype(int), 0, zoom - 1)
    tj = np.clip((rc[:, 1] * zoom // w).astype(int), 0, zoom - 1)
    hist = np.bincount(ti * zoom + tj, minlength=zoom * zoom)
    best = np.argsort(-hist, kind="stable")[: int(count)]
    return np.stack([best // zoom, best % zoom], axis=-1)


def tile_camera(guide: Camera, tile, zoom: int, receiver_px) -> Camera:
    """The receiver of a revisit: ``guide``'s pose, its field narrowed to one tile of a
    zoom x zoom grid (an off-centre principal point), ``receiver_px`` (rows, cols) pixels."""
    k = guide.intrinsics
    rh, rw = receiver_px
    s = rw * zoom / k.width  # receiver px per guide px
    u0, v0 = tile[1] * k.width / zoom, tile[0] * k.height / zoom
    kk = Intrinsics(k.fx * s, k.fy * s, (k.cx - u0) * s, (k.cy - v0) * s, rw, rh)
    return Camera(kk, guide.pose)


class FlashLidar:
    """A flash LIDAR co-boresighted with the guide camera, with optional plan-directed revisits.

    Parameters
    ----------
    scene : LidarScene
    options : FlashLidarOptions, optional
    """

    name = "flash"

    def __init__(self, scene: LidarScene, options: FlashLidarOptions | None = None) -> None:
        self.scene = scene
        self.options = options or FlashLidarOptions()
        rh, rw = self.options.receiver_px
        k = scene.camera.intrinsics
        self.receiver = Camera(k.scaled(rw / k.width), scene.camera.pose)
        if self.receiver.shape != (rh, rw):
            raise ValueError(
                f"receiver_px {(rh, rw)} must keep the guide camera's aspect {k.shape}"
            )
        self._frames: dict = {}

    @property
    def needs_plan(self) -> bool:
        return self.options.revisits > 0 and self.options.revisit_from != "ranges"

    def _frame(self, camera: Camera, key, rng, moving=None, t: float = 0.0) -> LidarScan:
        """A frame through ``camera``: rendered once per field (``key``), read with fresh noise;
        on a moving platform (``moving``, a :class:`_Moving`) through the pose at time ``t``
        (rendered for that pose alone), its points placed with the sensor's navigation."""
        s, f = self.scene, self.options.flash
        if moving is not None:
            cam = moving.camera(camera, t)
            bins = flash_window(cam, options=f)
            frame = flash_frame(s.terrain, cam, bins=bins, options=f.transient, bsdf=s.bsdf,
                                sun=s.sun)  # fmt: skip
            return moving.place(read_flash(frame, cam, options=f, rng=rng), cam, t)
        if key not in self._frames:
            bins = flash_window(camera, options=f)
            self._frames[key] = flash_frame(
                s.terrain, camera, bins=bins, options=f.transient, bsdf=s.bsdf, sun=s.sun
            )
        return read_flash(self._frames[key], camera, options=f, rng=rng)

    def acquire(self, rc: np.ndarray | None, *, rng=None) -> Acquisition:
        """One full-field frame, then ``revisits`` zoomed frames at the sub-fields with most
        planned pixels ``rc`` ((k, 2) (row, col); ignored without revisits)."""
        o, cam = self.options, self.scene.camera
        g = np.random.default_rng(rng)
        rngs = g.spawn(1 + int(o.revisits))
        per_frame = o.flash.detector.pulses / o.flash.pulse_rate_hz
        moving = None if o.motion is None else _Moving(o.motion, cam.position, g)
        full = self._frame(self.receiver, None, rngs[0], moving, 0.0)
        scans = [full]
        tiles = np.zeros((0, 2), int)
        if o.revisits > 0:
            if rc is None and o.revisit_from != "ranges":
                raise ValueError("flash revisits are directed by a plan: rc is required")
            tiles = self._revisit_tiles(rc, full)
            for i, (t, r) in enumerate(zip(tiles, rngs[1:]), 1):
                tcam = tile_camera(cam, t, o.zoom, o.receiver_px)
                when = i * (per_frame + o.repoint_s)  # each revisit re-points first
                scans.append(self._frame(tcam, tuple(int(x) for x in t), r, moving, when))
        flat = [flat_scan(s) for s in scans]
        if len(tiles):
            # the finer revisit samples supersede the full frame's inside their tiles
            uv, _ = cam.project(np.where(flat[0].valid[:, None], flat[0].points, 0.0))
            t = np.stack([uv[:, 1] * o.zoom // cam.shape[0], uv[:, 0] * o.zoom // cam.shape[1]], -1)
            inside = (t[:, None, :] == tiles[None]).all(-1).any(-1)
            flat[0] = subset_scan(flat[0], ~inside)
        merged = concat_scans(flat)
        seconds = len(scans) * per_frame + len(tiles) * o.repoint_s
        return _to_guide(merged, cam, frames=len(scans), seconds=seconds, detail=merged)

    def _revisit_tiles(self, rc, full: LidarScan) -> np.ndarray:
        """The revisits' tiles from the plan, the full frame's own ranges, or both."""
        o, cam = self.options, self.scene.camera
        plan_counts = rough = None
        if o.revisit_from != "ranges":
            if o.revisit_from == "plan":
                return revisit_tiles(rc, cam.shape, o.zoom, o.revisits)
            plan_counts = _tile_counts(rc, cam.shape, o.zoom)
        rough = tile_range_scores(full.points, full.valid, o.zoom)
        return choose_tiles(plan_counts, rough, o.revisits, range_weight=o.range_weight)


class _Moving:
    """A flash LIDAR on a moving platform: the receiver's pose at a frame's time and the
    points as the sensor places them (:mod:`simlunar.lidar.trajectory`)."""

    def __init__(self, motion: PlatformMotion, start, rng) -> None:
        self.motion = motion
        self.rng = rng
        self.trajectory = motion.trajectory(start, jitter_seed=int(rng.integers(2**31)))

    def camera(self, camera: Camera, t: float) -> Camera:
        """``camera`` moved to the platform's position at ``t`` (s), turned by its jitter."""
        return camera_at(camera, self.trajectory, t)

    def place(self, scan: LidarScan, camera: Camera, t: float) -> LidarScan:
        """``scan`` (read through the moved ``camera``) with its points placed by the
        navigation: commanded directions are the receiver pixels' rays before the jitter."""
        _, d = camera.rays(camera.pixel_centers())
        d = d.reshape(-1, 3)
        commanded = rotate_small(d, np.broadcast_to(-self.trajectory.attitude_at(t), d.shape))
        times = np.full(d.shape[0], float(t))
        pts = place_points(scan.ranges.ravel(), commanded, times, self.trajectory,
                           self.motion.navigation, rng=self.rng)  # fmt: skip
        return dataclasses.replace(scan, points=pts.reshape(scan.points.shape))
