"""Pinhole and orthographic cameras, projectors and scanner rigs.

Conventions (CONTRIBUTING.md, "Conventions recap"):

* World frame right-handed, z up, metres.
* Device frames OpenCV-style: x right, y down, z forward (along the optical axis).
* Pixel coordinates (u, v) are continuous, u along columns, v along rows, with the centre of
  pixel (row r, col c) at (u, v) = (c + 0.5, r + 0.5). So a centred principal point is
  (cx, cy) = (width / 2, height / 2). OpenCV puts pixel centres at integers: convert with
  ``cx_opencv = cx - 0.5`` (see :meth:`Intrinsics.to_opencv`).
* A :class:`Pose` is camera-to-world: ``rotation`` has the camera's x, y, z axes (in world
  coordinates) as its columns and ``position`` is the centre of projection.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def _ro(a, dtype=np.float64) -> np.ndarray:
    arr = np.array(a, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


def _normalize(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(n == 0):
        raise ValueError("cannot normalise a zero-length vector")
    return v / n


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics in pixels (pixel centres at i + 0.5).

    Parameters
    ----------
    fx, fy : float
        Focal lengths in pixels.
    cx, cy : float
        Principal point in pixels (centred: ``width / 2, height / 2``).
    width, height : int
        Image size in pixels.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    def __post_init__(self) -> None:
        if not (self.fx > 0 and self.fy > 0):
            raise ValueError(f"focal lengths must be positive, got fx={self.fx}, fy={self.fy}")
        if int(self.width) <= 0 or int(self.height) <= 0:
            raise ValueError(f"image size must be positive, got {self.width}x{self.height}")
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))

    @classmethod
    def from_fov(cls, width: int, height: int, fov_x_deg: float) -> Intrinsics:
        """Square pixels, centred principal point, horizontal field of view in degrees."""
        if not 0 < fov_x_deg < 180:
            raise ValueError(f"fov_x_deg must be in (0, 180), got {fov_x_deg}")
        f = 0.5 * width / np.tan(np.radians(fov_x_deg) / 2)
        return cls(f, f, width / 2, height / 2, width, height)

    @property
    def K(self) -> np.ndarray:
        """3x3 calibration matrix mapping camera coordinates to (u, v, 1) (this convention)."""
        return np.array([[self.fx, 0, self.cx], [0, self.fy, self.cy], [0, 0, 1.0]])

    @property
    def shape(self) -> tuple[int, int]:
        """Image shape as (rows, cols)."""
        return (self.height, self.width)

    @property
    def fov_x_deg(self) -> float:
        return float(np.degrees(2 * np.arctan(self.width / (2 * self.fx))))

    @property
    def fov_y_deg(self) -> float:
        return float(np.degrees(2 * np.arctan(self.height / (2 * self.fy))))

    @property
    def is_centred(self) -> bool:
        return bool(np.isclose(self.cx, self.width / 2) and np.isclose(self.cy, self.height / 2))

    def to_opencv(self) -> np.ndarray:
        """Calibration matrix in OpenCV's convention (pixel centres at integers)."""
        K = self.K
        K[0, 2] -= 0.5
        K[1, 2] -= 0.5
        return K

    def scaled(self, factor: float) -> Intrinsics:
        """Same field of view at ``factor`` times the resolution."""
        return Intrinsics(
            self.fx * factor,
            self.fy * factor,
            self.cx * factor,
            self.cy * factor,
            round(self.width * factor),
            round(self.height * factor),
        )


@dataclass(frozen=True, eq=False)
class Pose:
    """Camera-to-world rigid transform.

    Parameters
    ----------
    rotation : (3, 3) array
        Columns are the device's x (right), y (down), z (forward) axes in world coordinates.
    position : (3,) array
        Centre of projection in world coordinates (m).
    """

    rotation: np.ndarray
    position: np.ndarray

    def __post_init__(self) -> None:
        R = _ro(self.rotation)
        t = _ro(self.position)
        if R.shape != (3, 3) or t.shape != (3,):
            raise ValueError(
                f"rotation must be 3x3 and position length 3, got {R.shape}, {t.shape}"
            )
        if not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
            raise ValueError("rotation must be a proper orthonormal matrix")
        object.__setattr__(self, "rotation", R)
        object.__setattr__(self, "position", t)

    @classmethod
    def look_at(cls, eye, target, up=(0.0, 0.0, 1.0)) -> Pose:
        """Device at ``eye`` looking at ``target``; image 'up' (-y) towards ``up``.

        For a view straight down (forward parallel to ``up``), +y world is taken as image up.
        """
        eye = np.asarray(eye, float)
        z = _normalize(np.asarray(target, float) - eye)
        up = np.asarray(up, float)
        if np.linalg.norm(np.cross(z, up)) < 1e-9:
            up = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
        x = _normalize(np.cross(z, up))
        y = np.cross(z, x)
        return cls(np.stack([x, y, z], axis=1), eye)

    @classmethod
    def from_heading(cls, eye, *, azimuth_deg: float, depression_deg: float) -> Pose:
        """Device at ``eye`` looking towards ``azimuth_deg`` (from +y clockwise towards +x),
        ``depression_deg`` below the horizon, with no roll (image x stays horizontal).

        At 90 deg (straight down) image up is the azimuth direction.
        """
        az, dep = np.radians(azimuth_deg), np.radians(depression_deg)
        z = np.array([np.cos(dep) * np.sin(az), np.cos(dep) * np.cos(az), -np.sin(dep)])
        x = np.array([np.cos(az), -np.sin(az), 0.0])  # right of the heading, horizontal
        y = np.cross(z, x)  # image down
        return cls(np.stack([x, y, z], axis=1), np.asarray(eye, float))

    @property
    def forward(self) -> np.ndarray:
        return self.rotation[:, 2]

    def world_to_device(self, points) -> np.ndarray:
        """(..., 3) world points to device coordinates."""
        return (np.asarray(points, float) - self.position) @ self.rotation

    def device_to_world(self, points) -> np.ndarray:
        """(..., 3) device points to world coordinates."""
        return np.asarray(points, float) @ self.rotation.T + self.position

    def extrinsics_opencv(self) -> tuple[np.ndarray, np.ndarray]:
        """(R, t) with x_cam = R x_world + t, as OpenCV's solvePnP/projectPoints use."""
        R = self.rotation.T
        return R.copy(), -R @ self.position


@dataclass(frozen=True, eq=False)
class Camera:
    """Pinhole camera: intrinsics plus camera-to-world pose.

    ``aperture_radius`` (m) and ``focus_distance`` (m) describe an optional thin lens
    (0 means pinhole).
    """

    intrinsics: Intrinsics
    pose: Pose
    aperture_radius: float = 0.0
    focus_distance: float | None = None

    def __post_init__(self) -> None:
        if self.aperture_radius < 0:
            raise ValueError(f"aperture_radius must be >= 0, got {self.aperture_radius}")
        if self.aperture_radius > 0 and not (self.focus_distance and self.focus_distance > 0):
            raise ValueError("a thin lens (aperture_radius > 0) needs focus_distance > 0")

    @property
    def shape(self) -> tuple[int, int]:
        return self.intrinsics.shape

    @property
    def position(self) -> np.ndarray:
        return self.pose.position

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """World points (..., 3) to pixel coordinates (..., 2) and depth z (...,) in metres.

        Points behind the camera get depth <= 0 (their (u, v) are meaningless).
        """
        pc = self.pose.world_to_device(points)
        z = pc[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = self.intrinsics.fx * pc[..., 0] / z + self.intrinsics.cx
            v = self.intrinsics.fy * pc[..., 1] / z + self.intrinsics.cy
        return np.stack([u, v], axis=-1), z

    def directions_device(self, uv) -> np.ndarray:
        """Unnormalised device-frame ray directions (x, y, 1) through pixel coordinates."""
        uv = np.asarray(uv, float)
        x = (uv[..., 0] - self.intrinsics.cx) / self.intrinsics.fx
        y = (uv[..., 1] - self.intrinsics.cy) / self.intrinsics.fy
        return np.stack([x, y, np.ones_like(x)], axis=-1)

    def rays(self, uv) -> tuple[np.ndarray, np.ndarray]:
        """Rays through pixel coordinates: world origins (..., 3) and unit directions (..., 3)."""
        d = _normalize(self.directions_device(uv) @ self.pose.rotation.T)
        o = np.broadcast_to(self.pose.position, d.shape).copy()
        return o, d

    def pixel_centers(self) -> np.ndarray:
        """(rows, cols, 2) array of (u, v) pixel-centre coordinates."""
        return pixel_centers(self.intrinsics.height, self.intrinsics.width)

    def unproject_depth(self, depth: np.ndarray) -> np.ndarray:
        """Depth map (rows, cols) of z-depths to world points (rows, cols, 3)."""
        d = self.directions_device(self.pixel_centers()) * np.asarray(depth, float)[..., None]
        return self.pose.device_to_world(d)


@dataclass(frozen=True, eq=False)
class Projector(Camera):
    """A pinhole projector; Mitsuba's projector emitter has no principal-point offset.

    ``width`` x ``height`` of the intrinsics is the pattern resolution (pattern shape is
    (height, width)).
    """

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.intrinsics.is_centred:
            raise ValueError(
                "projector principal point must be centred "
                f"(cx, cy) = ({self.intrinsics.width / 2}, {self.intrinsics.height / 2}), got "
                f"({self.intrinsics.cx}, {self.intrinsics.cy}): Mitsuba's projector emitter "
                "cannot shift it"
            )
        if not np.isclose(self.intrinsics.fx, self.intrinsics.fy):
            raise ValueError("projector pixels must be square (fx == fy)")


@dataclass(frozen=True, eq=False)
class OrthoCamera:
    """Orthographic camera looking along its z axis.

    Pixel (u, v) maps to device-plane point ((u - width/2) * pixel_size,
    (v - height/2) * pixel_size, 0). Build one whose pixels coincide with DEM cells with
    :meth:`nadir_for_grid`.
    """

    pose: Pose
    width: int
    height: int
    pixel_size: float

    def __post_init__(self) -> None:
        if self.pixel_size <= 0:
            raise ValueError(f"pixel_size must be positive, got {self.pixel_size}")
        if int(self.width) <= 0 or int(self.height) <= 0:
            raise ValueError(f"image size must be positive, got {self.width}x{self.height}")

    @classmethod
    def nadir_for_grid(
        cls, shape: tuple[int, int], spacing: float, origin=(0.0, 0.0), altitude: float = 1000.0
    ) -> OrthoCamera:
        """Nadir camera whose pixel (r, c) looks straight down at the centre of grid cell (r, c).

        The grid convention is that of :class:`simlunar.terrain.Terrain`: ``origin`` is the
        world (x, y) of the top-left (north-west) corner of cell (0, 0); columns run to +x,
        rows to -y.
        """
        rows, cols = shape
        x0, y0 = origin
        centre = np.array([x0 + cols * spacing / 2, y0 - rows * spacing / 2, altitude], float)
        # x right = +x world, y down = -y world, z forward = -z world
        R = np.array([[1.0, 0, 0], [0, -1.0, 0], [0, 0, -1.0]])
        return cls(Pose(R, centre), cols, rows, spacing)

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.height), int(self.width))

    @property
    def position(self) -> np.ndarray:
        return self.pose.position

    def rays(self, uv) -> tuple[np.ndarray, np.ndarray]:
        uv = np.asarray(uv, float)
        pd = np.stack(
            [
                (uv[..., 0] - self.width / 2) * self.pixel_size,
                (uv[..., 1] - self.height / 2) * self.pixel_size,
                np.zeros(uv.shape[:-1]),
            ],
            axis=-1,
        )
        o = self.pose.device_to_world(pd)
        d = np.broadcast_to(self.pose.forward, o.shape).copy()
        return o, d

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        pc = self.pose.world_to_device(points)
        u = pc[..., 0] / self.pixel_size + self.width / 2
        v = pc[..., 1] / self.pixel_size + self.height / 2
        return np.stack([u, v], axis=-1), pc[..., 2]

    def pixel_centers(self) -> np.ndarray:
        return pixel_centers(int(self.height), int(self.width))


@dataclass(frozen=True, eq=False)
class Rig:
    """Image-directed scanner: projector, guide camera co-located with it, offset camera.

    The guide camera shares the projector's centre of projection and intrinsics, so guide
    pixel (r, c) is projector pixel (r, c) (paper, section 5).
    """

    projector: Projector
    camera: Camera
    guide: Camera = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        if self.guide is None:
            object.__setattr__(
                self, "guide", Camera(self.projector.intrinsics, self.projector.pose)
            )
        baseline = float(np.linalg.norm(self.camera.position - self.projector.position))
        if baseline < 1e-9:
            raise ValueError(
                "rig baseline is zero: the triangulation camera must be offset from the projector"
            )

    @property
    def baseline(self) -> float:
        return float(np.linalg.norm(self.camera.position - self.projector.position))


def grid_height_at(heights, spacing: float, origin, x: float, y: float) -> float:
    """Bilinear height of a grid (cell centres, :class:`~simlunar.terrain.Terrain` frame) at
    world (x, y); nodata neighbours are left out of the weights.

    Raises
    ------
    ValueError
        (x, y) outside the grid's cell centres, or all four neighbours nodata.
    """
    h = np.asarray(heights, float)
    rows, cols = h.shape
    fc = (x - origin[0]) / spacing - 0.5
    fr = (origin[1] - y) / spacing - 0.5
    if not (0 <= fc <= cols - 1 and 0 <= fr <= rows - 1):
        raise ValueError(f"site ({x}, {y}) m lies outside the terrain's cell centres")
    c0, r0 = min(int(fc), cols - 2), min(int(fr), rows - 2)
    tc, tr = fc - c0, fr - r0
    z = h[r0 : r0 + 2, c0 : c0 + 2]
    w = np.array([[(1 - tr) * (1 - tc), (1 - tr) * tc], [tr * (1 - tc), tr * tc]])
    ok = np.isfinite(z)
    if not ok.any() or w[ok].sum() == 0:
        raise ValueError(f"site ({x}, {y}) m lies over nodata")
    return float((w[ok] * z[ok]).sum() / w[ok].sum())


def rover_mast_camera(
    heights: np.ndarray,
    spacing: float,
    origin: tuple[float, float] = (0.0, 0.0),
    *,
    site=None,
    height_above: float = 1.5,
    depression_deg: float = 30.0,
    azimuth_deg: float = 0.0,
    intrinsics: Intrinsics | None = None,
) -> Camera:
    """Pinhole camera on a rover mast over a height grid.

    Parameters
    ----------
    heights, spacing, origin
        The terrain grid (:class:`~simlunar.terrain.Terrain` frame).
    site : (x, y), optional
        World position of the mast foot; default the grid's centre.
    height_above : float
        Camera centre height above the (bilinear) ground at the site, metres.
    depression_deg, azimuth_deg : float
        Optical axis angle below the horizon, and heading from +y clockwise towards +x.
    intrinsics : Intrinsics, optional
        The image; default ``Intrinsics.from_fov(320, 240, 60.0)`` (320 x 240 px, square
        pixels, centred principal point, 60 degrees horizontal field of view).

    Returns
    -------
    Camera
    """
    rows, cols = np.shape(heights)
    if site is None:
        site = (origin[0] + cols * spacing / 2, origin[1] - rows * spacing / 2)
    if not height_above > 0:
        raise ValueError(f"height_above must be positive, got {height_above}")
    if not 0 < depression_deg <= 90:
        raise ValueError(f"depression_deg must be in (0, 90], got {depression_deg}")
    ground = grid_height_at(heights, spacing, origin, float(site[0]), float(site[1]))
    eye = (float(site[0]), float(site[1]), ground + height_above)
    pose = Pose.from_heading(eye, azimuth_deg=azimuth_deg, depression_deg=depression_deg)
    if intrinsics is None:
        intrinsics = Intrinsics.from_fov(320, 240, 60.0)
    return Camera(intrinsics, pose)


def pixel_centers(rows: int, cols: int) -> np.ndarray:
    """(rows, cols, 2) array of (u, v) = (c + 0.5, r + 0.5)."""
    v, u = np.mgrid[0:rows, 0:cols].astype(float)
    return np.stack([u + 0.5, v + 0.5], axis=-1)


# fmt: off
__all__ = [
    "Camera", "Intrinsics", "OrthoCamera", "Pose", "Projector",
    "Rig", "grid_height_at", "pixel_centers", "rover_mast_camera",
]
# fmt: on
