"""The guide of a unit's guided reconstructions: its frames and their light directions.

The guide view's image (the unit's own render) is the first frame; ``render.guide_frames``
adds frames of the SAME view -- the same terrain, camera, BSDF, render settings and sensor
model, each frame auto-exposed on its own as a camera would -- under another light:

* ``camera`` (also spelled ``ideal``): the IDEAL co-located light, a limiting case no rig has:
  a light at infinity on the optical axis (a directional light for the orthographic view; a
  point at the centre of a perspective camera), rendered with the sun off. At opposition the
  image is nearly pure albedo, so the ratio of a sun frame to it cancels albedo (the share of
  image variance the true slope explains falls from 0.62 at a 30 deg sun to 0.002 under
  camera-centred light); it becomes :attr:`Guide.flat <simlunar.reconstruction.Guide>`.
* ``{flash: {...}}``: a real flash on the rig (:class:`simlunar.render.lights.FlashLight`:
  a point emitter a baseline from the camera, inverse-square falloff, ``cos^n`` beam, its
  output in W/sr against the sun's W/m^2). At night (``daylight: false``) the frame is the
  flash alone; in daylight it is flash-on minus flash-off: the flash rendered alone, its
  radiance added to the guide view's, and both sums exposed as full frames with the sensor's
  noise at the exposure of the brighter (flash-on) one. It becomes the flat too, and with
  ``flat_field`` (on a nadir view) the guide carries the flash's geometry
  (:class:`~simlunar.reconstruction.flatfield.FlashGeometry`) so the reconstructions divide
  it by its falloff, incidence and beam on the samples' linear surface. Each light is
  rendered alone and the radiances added (one scene with both lights adds ~25 % per-pixel
  noise from emitter sampling).
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
from simlunar.config.render import (
    CameraLightCfg,
    GuideFlashFrameCfg,
    OrthoNadirCfg,
    SunLightCfg,
)
from simlunar.reconstruction import Guide
from simlunar.reconstruction.flatfield import FlashGeometry
from simlunar.render.scene import luminance

__all__ = [
    "CAMERA_FRAME",
    "FLASH_FRAME",
    "MAIN_SUN_FRAME",
    "build_guide",
    "flash_frame",
    "flash_geometry",
    "frame_name",
    "grid_light",
]

#: name of the camera-centred frame (the ideal co-located light)
CAMERA_FRAME = "camera"
#: name of a flash frame
FLASH_FRAME = "flash"
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
    """Name of a guide frame config: ``camera``, ``flash`` or ``sun_el<e>_az<a>`` (degrees)."""
    if isinstance(frame, str):
        return frame
    if isinstance(frame, GuideFlashFrameCfg):
        return FLASH_FRAME
    s = frame.sun
    return f"sun_el{s.elevation_deg:g}_az{s.azimuth_deg:g}"


def _main_name(light) -> str:
    return CAMERA_FRAME if isinstance(light, CameraLightCfg) else MAIN_SUN_FRAME


def flash_geometry(flash, camera, *, shape, spacing: float, origin) -> FlashGeometry:
    """The flash's :class:`~simlunar.reconstruction.flatfield.FlashGeometry` in the grid of a
    nadir view (``OrthoNadirCfg``: pixel (r, c) sees cell (r, c), sample values are depths
    below the camera's image plane).

    Cell (r, c) is centred at world ``(x0 + (c + 1/2) s, y0 - (r + 1/2) s)``, so a light at
    world ``(x, y, z)`` is at grid row ``(y0 - y) / s - 1/2``, column ``(x - x0) / s - 1/2``,
    depth ``altitude - z``; a world direction ``(dx, dy, dz)`` is ``(-dy, dx, dz)`` in
    ``(row, col, up)``.
    """
    position, axis = flash.pose(camera)
    x0, y0 = origin
    return FlashGeometry(
        row=(y0 - position[1]) / spacing - 0.5,
        col=(position[0] - x0) / spacing - 0.5,
        level=float(camera.pose.position[2] - position[2]),
        axis_row=-float(axis[1]),
        axis_col=float(axis[0]),
        axis_up=float(axis[2]),
        beam_exponent=flash.beam_exponent,
        cutoff=flash.cutoff,
        values="depth",
    )


def flash_frame(flash_radiance, *, develop, rng, sun_radiance=None) -> np.ndarray:
    """The co-located frame of a flash: at night (``sun_radiance`` None) the flash alone
    exposed as a frame; in daylight flash-on minus flash-off, two full exposures with the
    sensor's noise at the exposure of the brighter (flash-on) frame.

    Parameters
    ----------
    flash_radiance : ndarray, shape (rows, cols)
        The flash rendered alone (at night with the ambient term).
    develop : callable(radiance, rng, reference) -> image
        The sensor model, exposed on ``reference``'s radiance.
    rng : numpy.random.Generator or seed
        Noise of the frames (flash-on first, then flash-off).
    sun_radiance : ndarray, shape (rows, cols), optional
        The guide view's radiance under the sun (and the ambient term).

    Returns
    -------
    ndarray, float32 (rows, cols)
        The frame (in daylight a difference: it may be negative where the noise wins).
    """
    rng = np.random.default_rng(rng)
    if sun_radiance is None:
        return np.asarray(develop(flash_radiance, rng, flash_radiance), np.float32)
    on = np.asarray(sun_radiance, np.float64) + np.asarray(flash_radiance, np.float64)
    img_on = np.asarray(develop(on, rng, on), np.float64)
    img_off = np.asarray(develop(np.asarray(sun_radiance, np.float64), rng, on), np.float64)
    return (img_on - img_off).astype(np.float32)


def build_guide(
    cfg, scene, image: np.ndarray, seeds, *, develop, lock, timings=None, radiance=None
):
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
    develop : callable(radiance, rng, reference=None) -> image
        The unit's sensor model (radiance (rows, cols) -> image in [0, 1]), auto-exposed on
        ``reference`` (default: the radiance itself).
    lock : context manager
        Held around each render (the unit's render lock).
    timings : dict, optional
        Gets ``guide_frames_s``.
    radiance : ndarray, shape (rows, cols), optional
        The guide view's radiance (needed by a daylight flash frame: flash-on is it plus the
        flash's).

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
    flat, others, flash_geo, flat_frames = None, [], None, ("camera",)
    children = seeds.spawn(len(r.guide_frames)) if r.guide_frames else []
    for frame, ss in zip(r.guide_frames, children):
        name = frame_name(frame)
        if name == main:
            raise ValueError(f"render.guide_frames: {name} is the guide view's own light")
        camera = isinstance(frame, str)  # camera-centred
        if isinstance(frame, GuideFlashFrameCfg):
            flat, flash_geo = _flash(
                cfg, scene, frame.flash, ss, develop=develop, lock=lock, radiance=radiance
            )
            frames[name] = flat
            # flash-on and flash-off in daylight: two exposures for the one frame
            flat_frames = (f"{name}_on", f"{name}_off") if frame.flash.daylight else (name,)
            continue
        img, direction = _lit_frame(cfg, scene, frame, ss, nadir=nadir, develop=develop, lock=lock)
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
        frames=(main, *(f for n in frames for f in (flat_frames if n == FLASH_FRAME else (n,)))),
        flash=flash_geo,
        flat_frames=flat_frames,
    )
    return guide, frames


def _lit_frame(cfg, scene, frame, ss, *, nadir: bool, develop, lock):
    """A camera-centred (``frame`` a str) or sun-lit guide frame: its sensor image and its
    light direction (None: camera-centred, or a camera that is not the nadir one)."""
    if isinstance(frame, str):
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
        lights=translate.lights(light_cfg, cfg.render.ambient_radiance),
        seed=int(render_ss.generate_state(1, dtype=np.uint32)[0] & 0x7FFFFFFF),
    )
    with lock:
        result = lit.render()
    img = np.asarray(develop(luminance(result.image), np.random.default_rng(sensor_ss)))
    return img, direction


def _flash(cfg, scene, flash_cfg, ss, *, develop, lock, radiance):
    """A flash frame (:func:`flash_frame`) and its geometry (None: not flat-fielded)."""
    r = cfg.render
    sun = r.light if isinstance(r.light, SunLightCfg) else None
    light = translate.flash_light(flash_cfg, sun, scene.camera)
    daylight = flash_cfg.daylight
    if daylight and radiance is None:
        raise ValueError("a daylight flash frame needs the guide view's radiance")
    # in daylight the ambient term is in the guide view's radiance already
    lights = [light] if daylight else [light, *translate.lights(r.light, r.ambient_radiance)[1:]]
    render_ss, sensor_ss = ss.spawn(2)
    lit = dataclasses.replace(
        scene,
        lights=lights,
        seed=int(render_ss.generate_state(1, dtype=np.uint32)[0] & 0x7FFFFFFF),
    )
    with lock:
        result = lit.render()
    img = flash_frame(
        luminance(result.image),
        develop=develop,
        rng=np.random.default_rng(sensor_ss),
        sun_radiance=np.asarray(radiance, np.float64) if daylight else None,
    )
    geo = None
    if flash_cfg.flat_field and isinstance(r.camera, OrthoNadirCfg):
        t = scene.terrain
        geo = flash_geometry(
            light, scene.camera, shape=t.shape, spacing=float(t.spacing), origin=t.origin
        )
    return img, geo
