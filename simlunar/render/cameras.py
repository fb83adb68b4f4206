"""Mitsuba sensor dictionaries from :mod:`simlunar.geometry` cameras.

THE frame conversion between simlunar's device frames and Mitsuba's lives here.

* simlunar (OpenCV style): device x right, y down, z forward; pixel centre of (r, c) at
  (u, v) = (c + 0.5, r + 0.5).
* Mitsuba: a sensor looks along its local +z with local +x towards the image LEFT and +y
  towards the image TOP (checked by ``sample_ray`` in ``tests/render/test_cameras.py``).

So Mitsuba's camera basis is the OpenCV basis turned 180 degrees about the optical axis:
``R_mitsuba = R_opencv @ diag(-1, -1, 1)`` (a proper rotation, no mirror). Mitsuba's
``principal_point_offset_x/y`` are fractions of the film width/height, measured so that
``cx = width / 2 - offset_x * width`` and ``cy = height / 2 - offset_y * height``.

Only :func:`sensor_dict` and :func:`film_dict` need Mitsuba objects (via
:func:`simlunar.render.backend.mitsuba`); everything else is NumPy.
"""

from __future__ import annotations

import numpy as np

from simlunar.geometry import Camera, OrthoCamera, Pose
from simlunar.render import backend

__all__ = [
    "CV_TO_MITSUBA",
    "clip_range",
    "film_dict",
    "principal_point_offsets",
    "sensor_dict",
    "to_world_matrix",
    "view_direction",
]

#: OpenCV device axes -> Mitsuba sensor axes (x and y flipped, z kept)
CV_TO_MITSUBA = np.diag([-1.0, -1.0, 1.0])


def to_world_matrix(pose: Pose, scale=(1.0, 1.0, 1.0)) -> np.ndarray:
    """4x4 Mitsuba ``to_world`` of a device with OpenCV-style ``pose``.

    Parameters
    ----------
    pose : Pose
        Camera-to-world pose (OpenCV device axes as columns).
    scale : (3,) floats
        Scale applied in the Mitsuba local frame before rotation (orthographic extent only;
        Mitsuba forbids scale on perspective sensors).

    Returns
    -------
    (4, 4) float64 array.
    """
    m = np.eye(4)
    m[:3, :3] = pose.rotation @ CV_TO_MITSUBA @ np.diag(np.asarray(scale, float))
    m[:3, 3] = pose.position
    return m


def principal_point_offsets(camera: Camera) -> tuple[float, float]:
    """Mitsuba ``principal_point_offset_x/y`` for ``camera``'s (cx, cy) (film fractions)."""
    k = camera.intrinsics
    return ((k.width / 2 - k.cx) / k.width, (k.height / 2 - k.cy) / k.height)


def film_dict(width: int, height: int) -> dict:
    """Linear float32 RGB film with a box filter (pixels do not share samples)."""
    return {
        "type": "hdrfilm",
        "width": int(width),
        "height": int(height),
        "rfilter": {"type": "box"},
        "pixel_format": "rgb",
        "component_format": "float32",
    }


def clip_range(camera, bounds: tuple[np.ndarray, np.ndarray] | None) -> tuple[float, float]:
    """Near and far clip distances that enclose ``bounds`` (world AABB min, max) from the camera."""
    if bounds is None:
        return 1e-3, 1e5
    lo, hi = (np.asarray(b, float) for b in bounds)
    corners = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    far = float(np.max(np.linalg.norm(corners - camera.pose.position, axis=1)))
    far = 2.0 * far + 1.0
    near = max(far * 1e-7, 1e-4)
    return near, far


def sensor_dict(camera, *, spp: int = 16, bounds=None) -> dict:
    """Mitsuba sensor dictionary for a :class:`Camera` or :class:`OrthoCamera`.

    Parameters
    ----------
    camera : geometry.Camera or geometry.OrthoCamera
        Perspective pinhole (optionally thin lens) or orthographic camera.
    spp : int
        Samples per pixel of the ``independent`` sampler (``render`` may override it).
    bounds : (min (3,), max (3,)) or None
        World bounding box of the scene, used to choose clip planes.

    Raises
    ------
    ValueError
        Unknown camera type, non-square pixels (``fx != fy``: Mitsuba's perspective sensor
        has square pixels and forbids scale in ``to_world``), or a thin lens with an
        off-centre principal point (Mitsuba's ``thinlens`` has no principal-point offset).
    """
    mi = _mi()
    near, far = clip_range(camera, bounds)
    if isinstance(camera, OrthoCamera):
        # Mitsuba's orthographic sensor spans x in [-1, 1] and y in [-1/aspect, 1/aspect]
        # before to_world: scaling by half the film width in metres makes pixels pixel_size wide
        s = camera.width * camera.pixel_size / 2
        d = {
            "type": "orthographic",
            "to_world": mi.ScalarTransform4f(to_world_matrix(camera.pose, (s, s, 1.0))),
            "film": film_dict(camera.width, camera.height),
        }
    elif isinstance(camera, Camera):
        k = camera.intrinsics
        if not np.isclose(k.fx, k.fy, rtol=1e-9):
            raise ValueError(
                f"camera.intrinsics: fx={k.fx} != fy={k.fy}; Mitsuba's perspective sensor needs "
                "square pixels (resample the image or use fx == fy)"
            )
        ox, oy = principal_point_offsets(camera)
        d = {
            "type": "perspective",
            "fov_axis": "x",
            "fov": k.fov_x_deg,
            "to_world": mi.ScalarTransform4f(to_world_matrix(camera.pose)),
            "film": film_dict(k.width, k.height),
        }
        if camera.aperture_radius > 0:
            if abs(ox) > 1e-12 or abs(oy) > 1e-12:
                raise ValueError(
                    "camera: a thin lens (aperture_radius > 0) needs a centred principal point "
                    f"(cx, cy) = ({k.width / 2}, {k.height / 2}), got ({k.cx}, {k.cy}); "
                    "Mitsuba's thinlens sensor has no principal-point offset"
                )
            d["type"] = "thinlens"
            d["aperture_radius"] = float(camera.aperture_radius)
            d["focus_distance"] = float(camera.focus_distance)
        else:
            d["principal_point_offset_x"] = float(ox)
            d["principal_point_offset_y"] = float(oy)
    else:
        raise ValueError(
            f"camera: unknown camera type {type(camera).__name__}; valid: Camera "
            "(perspective / thin lens), OrthoCamera (orthographic)"
        )
    d["near_clip"] = near
    d["far_clip"] = far
    d["sampler"] = {"type": "independent", "sample_count": int(spp)}
    return d


def view_direction(camera) -> np.ndarray:
    """Unit world direction of the optical axis (device +z)."""
    return np.asarray(camera.pose.forward, float)


def _mi():

    return backend.mitsuba()
