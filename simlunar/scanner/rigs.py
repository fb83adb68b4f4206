"""Scanner rig presets built from :mod:`simlunar.geometry` (NumPy only).

A rig is a pinhole projector with a centred principal point, a guide camera co-located with it
(same centre and intrinsics: guide pixel (r, c) is projector pixel (r, c), paper section 5) and a
triangulation camera offset along the projector's x axis (so epipolar lines run roughly along
camera rows and gray-code columns carry the depth).
"""

from __future__ import annotations

import numpy as np

from simlunar.geometry import Camera, Intrinsics, Pose, Projector, Rig


def make_rig(
    *,
    target,
    distance: float,
    elevation: float,
    azimuth: float = 0.0,
    baseline: float,
    proj_size: tuple[int, int] = (1024, 768),
    proj_fov_x: float,
    cam_size: tuple[int, int] = (1024, 768),
    cam_fov_x: float | None = None,
    verge: bool = True,
    aperture_radius: float = 0.0,
    focus_distance: float | None = None,
) -> Rig:
    """Projector looking at ``target`` from ``distance``; camera offset by ``baseline``.

    Parameters
    ----------
    target : (3,) world point the projector's optical axis passes through (m)
    distance : projector centre to target (m), > 0
    elevation : angle of the projector above the target's horizon (rad, pi/2 = nadir)
    azimuth : direction from target to projector, clockwise from +y (north) towards +x (rad)
    baseline : offset of the triangulation camera along the projector's x axis (m); must not be 0
    proj_size, cam_size : (width, height) in pixels
    proj_fov_x, cam_fov_x : horizontal fields of view (rad); ``cam_fov_x`` defaults to the projector's
    verge : if True the camera looks at ``target``; else its axis is parallel to the projector's
    aperture_radius, focus_distance : camera thin lens (m); 0 = pinhole; focus defaults to the
        camera-target distance

    Returns
    -------
    Rig
    """
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
    if verge:
        cpose = Pose.look_at(cam_eye, target, up=-ppose.rotation[:, 1])
    else:
        cpose = Pose(ppose.rotation, cam_eye)
    cw, ch = cam_size
    cK = Intrinsics.from_fov(cw, ch, np.degrees(cam_fov_x if cam_fov_x is not None else proj_fov_x))
    if aperture_radius > 0 and focus_distance is None:
        focus_distance = float(np.linalg.norm(target - cam_eye))
    camera = Camera(cK, cpose, aperture_radius=aperture_radius, focus_distance=focus_distance)
    return Rig(projector, camera)


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
    """
    return make_rig(
        target=target,
        distance=distance,
        elevation=elevation,
        baseline=baseline,
        proj_size=proj_size,
        proj_fov_x=fov_x,
        cam_size=cam_size,
        **kw,
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
    base-to-height ratio of 0.15.
    """
    return make_rig(
        target=target,
        distance=altitude,
        elevation=np.pi / 2,
        baseline=baseline,
        proj_size=proj_size,
        proj_fov_x=fov_x,
        cam_size=cam_size,
        **kw,
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
