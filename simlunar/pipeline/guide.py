"""The guide of a unit's guided reconstructions: its frames and their light directions.

The guide view's image (the unit's own render) is the first frame; ``render.guide_frames``
adds frames of the SAME view -- the same terrain, camera, BSDF, render settings and sensor
model, each frame auto-exposed on its own as a camera would -- under another light:

* ``camera``: camera-centred light. At opposition the image is nearly pure albedo, so the ratio
  of a sun frame to it cancels albedo (REFERENCES, 2026-11-28: the share of image variance the
  true slope explains falls from 0.62 at a 30 deg sun to 0.002 under camera-centred light);
  it becomes :attr:`Guide.flat <simlunar.reconstruction.Guide>`.
* ``{sun: {elevation_deg, azimuth_deg}}``: another sun (photometric stereo); each becomes one
  of :attr:`Guide.others`.

Light directions are given in grid coordinates ``(d_row, d_col, up)`` for an orthographic
nadir view only (pixel (r, c) sees cell (r, c)): rows run south (-y), columns east (+x)
(:meth:`simlunar.geometry.OrthoCamera.nadir_for_grid`), so a sun at elevation e and azimuth a
(from north, clockwise towards east; :func:`simlunar.render.lights.sun_direction`) is
``(-cos e cos a, cos e sin a, sin e)`` (:func:`grid_light`); camera-centred light on a nadir
view is ``(0, 0, 1)``. Any other view gets None (the reconstruction calibrates the direction
from the samples and the image).

What the sampling study measures is DEPTH (camera distance), which falls where height rises:
``up`` here is up out of the surface, i.e. towards decreasing sample values. A reconstruction
that relates the samples to the image must therefore fit a signed gain (the shading
calibration fits ``I ~ a + b . grad z`` by least squares, so the sign of ``b`` absorbs it).

Every frame is an exposure: each result row records the frames its reconstruction read
(``guide_frames``) and their count (``exposures``).
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from simlunar.config import translate
from simlunar.config.render import CameraLightCfg, OrthoNadirCfg, SunLightCfg
from simlunar.reconstruction import Guide
from simlunar.render.scene import luminance

__all__ = ["CAMERA_FRAME", "MAIN_SUN_FRAME", "build_guide", "frame_name", "grid_light"]

#: name of the camera-centred frame
CAMERA_FRAME = "camera"
#: name of the guide view's own frame when its light is a sun
MAIN_SUN_FRAME = "sun"


def grid_light(elevation: float, azimuth: float) -> np.ndarray:
    """Unit vector towards a sun in the grid coordinates of a nadir view.

    Parameters
    ----------
    elevation, azimuth : float
        Sun elevation above the horizon and azimuth from north (+y) clockwise towards east
        (+x), rad.

    Returns
    -------
    ndarray, shape (3,)
        ``(d_row, d_col, up) = (-cos e cos a, cos e sin a, sin e)``: rows point south (-y),
        columns east (+x), up out of the surface.
    """
    ce = math.cos(elevation)
    return np.array([-ce * math.cos(azimuth), ce * math.sin(azimuth), math.sin(elevation)])


def frame_name(frame) -> str:
    """Name of a guide frame config: ``camera`` or ``sun_el<e>_az<a>`` (degrees)."""
    if isinstance(frame, str):
        return frame
    s = frame.sun
    return f"sun_el{s.elevation_deg:g}_az{s.azimuth_deg:g}"


def _main_name(light) -> str:
    return CAMERA_FRAME if isinstance(light, CameraLightCfg) else MAIN_SUN_FRAME


def build_guide(cfg, scene, image: np.ndarray, seeds, *, develop, lock, timings=None):
    """The :class:`~simlunar.reconstruction.Guide` of a unit and its extra frames.

    Parameters
    ----------
    cfg : ExperimentCfg
        ``render.light``, ``render.camera``, ``render.guide_frames``, ``render.sensor``.
    scene : RenderScene
        The unit's scene (its lights are replaced per frame; the ambient term stays).
    image : ndarray, shape (rows, cols)
        The guide view's sensor image (the first frame).
    seeds : numpy.random.SeedSequence
        The unit's ``guide`` stage; frame i renders and exposes with its child i.
    develop : callable(radiance, rng) -> image
        The unit's sensor model (radiance (rows, cols) -> image in [0, 1]).
    lock : context manager
        Held around each render (the unit's render lock).
    timings : dict, optional
        Gets ``guide_frames_s``.

    Returns
    -------
    guide : Guide
    frames : dict name -> ndarray float32 (rows, cols)
        The extra frames (not the first).
    """
    r = cfg.render
    nadir = isinstance(r.camera, OrthoNadirCfg)
    main = _main_name(r.light)
    if isinstance(r.light, SunLightCfg):
        light = grid_light(r.light.elevation, r.light.azimuth) if nadir else None
    else:
        light = np.array([0.0, 0.0, 1.0]) if nadir else None
    t = time.perf_counter()
    frames: dict[str, np.ndarray] = {}
    flat, others = None, []
    children = seeds.spawn(len(r.guide_frames)) if r.guide_frames else []
    for frame, ss in zip(r.guide_frames, children):
        name = frame_name(frame)
        if name == main:
            raise ValueError(f"render.guide_frames: {name} is the guide view's own light")
        camera = isinstance(frame, str)  # camera-centred
        if camera:
            light_cfg = CameraLightCfg(kind="camera")
            direction = None
        else:
            s = frame.sun
            light_cfg = SunLightCfg(
                elevation_deg=s.elevation_deg, azimuth_deg=s.azimuth_deg, irradiance=s.irradiance
            )
            direction = grid_light(light_cfg.elevation, light_cfg.azimuth) if nadir else None
        render_ss, sensor_ss = ss.spawn(2)
        lit = dataclasses.replace(
            scene,
            lights=translate.lights(light_cfg, r.ambient_radiance),
            seed=int(render_ss.generate_state(1, dtype=np.uint32)[0] & 0x7FFFFFFF),
        )
        with lock:
            result = lit.render()
        img = np.asarray(develop(luminance(result.image), np.random.default_rng(sensor_ss)))
        frames[name] = img.astype(np.float32)
        if camera:
            flat = img
        else:
            others.append((img, direction))
    if timings is not None:
        timings["guide_frames_s"] = time.perf_counter() - t
    guide = Guide(
        image,
        light=light,
        flat=flat,
        others=tuple(others),
        spacing=float(scene.terrain.spacing),
        frames=(main, *frames),
    )
    return guide, frames
