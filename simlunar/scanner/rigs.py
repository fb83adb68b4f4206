"""Scanner rig presets built from :mod:`simlunar.geometry` (NumPy only).

A rig is a pinhole projector with a centred principal point, a guide camera co-located with it
(same centre and intrinsics: guide pixel (r, c) is projector pixel (r, c), paper section 5) and a
triangulation camera offset along the projector's x axis (so epipolar lines run roughly along
camera rows and gray-code columns carry the depth).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Camera, Intrinsics, Pose, Projector, Rig

__all__ = [
    "RIG_PRESETS",
    "RigCamera",
    "aerial_rig",
    "footprint",
    "make_rig",
    "moonyard_rig",
    "rig_preset",
]


@dataclass(frozen=True)
class RigCamera:
    """The triangulation camera of :func:`make_rig` (its position comes from the projector's pose
    and the baseline).

    Parameters
    ----------
    size : (width, height) in pixels
    fov_x : horizontal field of view (rad); None = the projector's
    verge : if True the camera looks at the target; else its axis is parallel to the projector's
    aperture_radius, focus_distance : thin lens (m); 0 = pinhole; focus defaults to the
        camera-target distance
    """

    size: tuple[int, int] = (1024, 768)
    fov_x: float | None = None
    verge: bool = True
    aperture_radius: float = 0.0
    focus_distance: float | None = None


#: the presets' camera keywords (also those of :func:`rig_preset`) and their RigCamera fields
_CAMERA_KEYWORDS = {
    "cam_fov_x": "fov_x",
    "verge": "verge",
    "aperture_radius": "aperture_radius",
    "focus_distance": "focus_distance",
}


def make_rig(
    *,
    target,
    distance: float,
    elevation: float,
    azimuth: float = 0.0,
    baseline: float,
    proj_size: tuple[int, int] = (1024, 768),
    proj_fov_x: float,
    camera: RigCamera | None = None,
) -> Rig:
    """Projector looking at ``target`` from ``distance``; camera offset by ``baseline``.

    Parameters
    ----------
    target : (3,) world point the projector's optical axis passes through (m)
    distance : projector centre to target (m), > 0
    elevation : angle of the projector above the target's horizon (rad, pi/2 = nadir)
    azimuth : direction from target to projector, clockwise from +y (north) towards +x (rad)
    baseline : offset of the triangulation camera along the projector's x axis (m); must not be 0
    proj_size : (width, height) in pixels
    proj_fov_x : horizontal field of view (rad)
    camera : RigCamera, optional
        Size, field of view, verging and lens of the triangulation camera (default
        ``RigCamera()``: 1024 x 768 px, the projector's field of view, verged, pinhole).

    Returns
    -------
    Rig
    """
    cam = RigCamera() if camera is None else camera
    if not distance > 0:
        raise ValueError(f"distance must be > 0 m, got {distance}")
    if not 0 < elevation <= np.pi / 2:
        raise ValueError(f"elevation must be in (0, pi/2] rad, got {elevation}")
    if abs(baseline) < 1e-9:
        raise ValueError(
            "baseline is zero: the triangulation camera must be offset from the projector"
        )
    target = np.asarray(target, float)
    horiz = np.array([np.sin(azimuth), np.cos(azimuth), 0.0])
    eye = target + distance * (np.cos(elevation) * horiz + np.array([0, 0, np.sin(elevation)]))
    # image 'up' points away from the target horizontally so the scene is upright in the image
    ppose = Pose.look_at(eye, target, up=(0.0, 0.0, 1.0))
    pw, ph = proj_size
    pK = Intrinsics.from_fov(pw, ph, np.degrees(proj_fov_x))
    projector = Projector(pK, ppose)
    cam_eye = eye + baseline * ppose.rotation[:, 0]
    if cam.verge:
        cpose = Pose.look_at(cam_eye, target, up=-ppose.rotation[:, 1])
    else:
        cpose = Pose(ppose.rotation, cam_eye)
    cw, ch = cam.size
    cK = Intrinsics.from_fov(cw, ch, np.degrees(cam.fov_x if cam.fov_x is not None else proj_fov_x))
    focus_distance = cam.focus_distance
    if cam.aperture_radius > 0 and focus_distance is None:
        focus_distance = float(np.linalg.norm(target - cam_eye))
    camera = Camera(cK, cpose, aperture_radius=cam.aperture_radius, focus_distance=focus_distance)
    return Rig(projector, camera)


def _camera_keywords(kw: dict, cam_size) -> dict:
    """A preset's extra keywords for :func:`make_rig`: the camera ones (``cam_fov_x``,
    ``verge``, ``aperture_radius``, ``focus_distance``) gathered with ``cam_size`` into
    ``camera``, the others (``azimuth``) as they are."""
    if "camera" in kw:
        raise TypeError(
            "a rig preset takes the camera as cam_size, cam_fov_x, verge, aperture_radius and "
            "focus_distance, not camera="
        )
    cam = {field: kw[key] for key, field in _CAMERA_KEYWORDS.items() if key in kw}
    rest = {k: v for k, v in kw.items() if k not in _CAMERA_KEYWORDS}
    return {"camera": RigCamera(size=cam_size, **cam), **rest}


def moonyard_rig(
    *,
    target=(0.0, 0.0, 0.0),
    proj_size=(1024, 768),
    cam_size=(1024, 768),
    distance: float = 1.6,
    elevation: float = np.radians(70.0),
    baseline: float = 0.35,
    fov_x: float = np.radians(50.0),
    **kw,
) -> Rig:
    """Bench-top standoff over the 2 m x 1.3 m moonyard (paper section 4.2 / 5).

    Defaults: projector 1.6 m from the target at 70 deg elevation, 50 deg horizontal field of view
    (about 1.5 m across at the target), camera 0.35 m to the side, verged on the target.
    Further keywords: ``azimuth`` and the camera's ``cam_fov_x``, ``verge``,
    ``aperture_radius``, ``focus_distance`` (:class:`RigCamera`).
    """
    return make_rig(
        target=target,
        distance=distance,
        elevation=elevation,
        baseline=baseline,
        proj_size=proj_size,
        proj_fov_x=fov_x,
        **_camera_keywords(kw, cam_size),
    )


def aerial_rig(
    *,
    target=(0.0, 0.0, 0.0),
    proj_size=(1024, 768),
    cam_size=(1024, 768),
    altitude: float = 100.0,
    baseline: float = 15.0,
    fov_x: float = np.radians(30.0),
    **kw,
) -> Rig:
    """Aerial altimeter geometry: nadir projector at ``altitude`` m, camera ``baseline`` m aside.

    The defaults give a 54 m wide footprint (5 cm projector pixels at 1024 columns) and a
    base-to-height ratio of 0.15. Further keywords as for :func:`moonyard_rig`.
    """
    return make_rig(
        target=target,
        distance=altitude,
        elevation=np.pi / 2,
        baseline=baseline,
        proj_size=proj_size,
        proj_fov_x=fov_x,
        **_camera_keywords(kw, cam_size),
    )


RIG_PRESETS = {"moonyard": moonyard_rig, "aerial": aerial_rig}


def rig_preset(name: str, **kw) -> Rig:
    """Rig preset by name (``moonyard``, ``aerial``); keyword options go to the preset."""
    try:
        fn = RIG_PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown rig preset {name!r}; valid: {sorted(RIG_PRESETS)}") from None
    return fn(**kw)


def footprint(rig: Rig, depth: float) -> float:
    """Size (m) of one projector pixel at z-depth ``depth`` m (the guide view's pixel footprint)."""
    return float(depth / rig.projector.intrinsics.fx)
