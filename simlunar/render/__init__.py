"""Rendering with Mitsuba 3: the only package of simlunar that imports mitsuba or drjit.

Importing this package does not import Mitsuba; :func:`simlunar.render.backend.init` does
(called on first use of anything that renders). Public names are resolved lazily:

- lights (NumPy specs): ``SunLight``, ``CameraLight``, ``ProjectorLight``, ``AmbientLight``,
  ``LIGHTS``, ``make_light``
- scene: ``TerrainScene``, ``render``, ``RenderResult``, ``inverse_by_linearity``,
  ``luminance``
- BSDF specs: ``LambertBSDF``, ``OrenNayarBSDF``, ``HapkeBSDF``, ``make_bsdf``
- mesh / cameras: ``terrain_mesh``, ``sensor_dict``
- time of flight (mitransient): ``TransientOptions``, ``FlashFrame``, ``flash_frame``,
  ``BeamCapture``, ``BeamReturns``, ``capture_beams``, ``beam_capture``; rendered flash
  LIDARs: ``flash_scan``, ``micromirror_flash`` (the LIDARs' options, ordering, photon counts
  and ranging are :mod:`simlunar.lidar`'s: :mod:`~simlunar.lidar.scan`,
  :mod:`~simlunar.lidar.flash`, :mod:`~simlunar.lidar.returns`)
- :mod:`simlunar.render.specs` gathers every light and BSDF spec (NumPy only)
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "SunLight": "lights",
    "CameraLight": "lights",
    "ProjectorLight": "lights",
    "AmbientLight": "lights",
    "LIGHTS": "lights",
    "make_light": "lights",
    "SUN_ANGULAR_DIAMETER": "lights",
    "TerrainScene": "scene",
    "render": "scene",
    "RenderResult": "scene",
    "inverse_by_linearity": "scene",
    "luminance": "scene",
    "LambertBSDF": "materials",
    "OrenNayarBSDF": "materials",
    "HapkeBSDF": "materials",
    "make_bsdf": "materials",
    "terrain_mesh": "mesh",
    "sensor_dict": "cameras",
    "TransientOptions": "transient",
    "FlashFrame": "transient",
    "flash_frame": "transient",
    "BeamCapture": "beam_capture",
    "BeamReturns": "beam_capture",
    "capture_beams": "beam_capture",
    "beam_capture": "beam_capture",
    "flash_scan": "flash_lidar",
    "micromirror_flash": "flash_lidar",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    try:
        module = _EXPORTS[name]
    except KeyError:
        raise AttributeError(f"module 'simlunar.render' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f"simlunar.render.{module}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
