"""Light specifications (NumPy only) and their conversion to Mitsuba emitters.

Specs are frozen dataclasses in SI units and radians. :func:`emitter_dicts` turns a spec
into Mitsuba emitter dictionaries; Mitsuba is imported lazily (only there), so this module is
importable without Mitsuba.

Solar disk
----------
The sun subtends about 0.53 degrees. A delta ``directional`` emitter gives hard shadows. For
``angular_diameter > 0`` we replace it by ``disk_samples`` directional emitters whose
directions are spread uniformly in solid angle over the solar disk (a golden-angle spiral with
``cos(r) = 1 - (i + 1/2)/m (1 - cos(alpha))``, mirrored in pairs), with equal weights
scaled so that a surface facing the sun receives exactly ``irradiance``. That preserves the
total irradiance on every surface orientation (the quadrature's centroid is the disk centre), integrates the disk with a deterministic quadrature,
and gives a penumbra of ``n`` steps. A far-away sphere emitter was rejected: in float32 it
cannot be both far enough for negligible parallax across the terrain (< 1 % of the disk) and
near enough for a precise ray/sphere test. Mitsuba picks one emitter per light sample
uniformly, so the disk costs no render time but increases the variance of other lights in the
same scene by the share of samples the sun takes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Camera, OrthoCamera, Projector, point_irradiance
from simlunar.registry import Options, option
from simlunar.render import backend
from simlunar.render.cameras import to_world_matrix

__all__ = [
    "LIGHTS",
    "PROJECTOR_ID",
    "SUN_ANGULAR_DIAMETER",
    "AmbientLight",
    "CameraLight",
    "FlashLight",
    "ProjectorLight",
    "SunLight",
    "check_pattern",
    "emitter_dicts",
    "make_light",
    "sun_direction",
]

SUN_ANGULAR_DIAMETER = np.radians(0.53)  # mean apparent diameter of the sun from the Moon


@dataclass(frozen=True)
class SunLight(Options):
    """Distant sun.

    ``angular_diameter`` 0 gives a point-like sun (hard shadows), ``SUN_ANGULAR_DIAMETER``
    (0.53 deg) the real one (soft shadows).
    """

    elevation: float = option(doc="angle above the horizon", unit="rad", gt=0, le=np.pi / 2)
    azimuth: float = option(doc="measured from +y (north) clockwise towards +x (east)", unit="rad")
    irradiance: float = option(
        1.0, doc="irradiance on a surface facing the sun (any consistent unit)", unit="W/m^2", ge=0
    )
    angular_diameter: float = option(
        0.0, doc="apparent diameter of the solar disk", unit="rad", ge=0, lt=np.pi / 2
    )
    disk_samples: int = option(
        32,
        doc="directions used to integrate the disk when angular_diameter > 0 (rounded up to an "
        "even number: the directions come in mirrored pairs)",
        ge=1,
    )

    @property
    def direction(self) -> np.ndarray:
        """Unit world vector pointing from the ground towards the sun's centre."""
        return sun_direction(self.elevation, self.azimuth)

    def directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Quadrature over the disk: unit directions to the sun (n, 3) and irradiances (n,)."""
        s = self.direction
        if self.angular_diameter == 0:
            return s[None, :], np.array([float(self.irradiance)])
        m = (int(self.disk_samples) + 1) // 2
        half = self.angular_diameter / 2
        i = np.arange(m) + 0.5
        cos_r = 1.0 - i / m * (1.0 - np.cos(half))  # uniform in solid angle over the cap
        sin_r = np.sqrt(np.maximum(0.0, 1.0 - cos_r**2))
        phi = np.arange(m) * np.pi * (3.0 - np.sqrt(5.0))  # golden angle
        # mirrored pairs (phi, phi + pi) put the quadrature's centroid exactly on the axis
        cos_r, sin_r, phi = (
            np.concatenate([cos_r, cos_r]),
            np.concatenate([sin_r, sin_r]),
            np.concatenate([phi, phi + np.pi]),
        )
        t1 = np.cross(s, [0.0, 0.0, 1.0] if abs(s[2]) < 0.9 else [1.0, 0.0, 0.0])
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(s, t1)
        d = cos_r[:, None] * s + sin_r[:, None] * (
            np.cos(phi)[:, None] * t1 + np.sin(phi)[:, None] * t2
        )
        # weights so that a plane facing the sun receives exactly ``irradiance``; any plane
        # then receives irradiance * cos(angle to the disk centre) (centroid on the axis)
        w = float(self.irradiance) / (len(d) * cos_r.mean())
        return d, np.full(len(d), w)


@dataclass(frozen=True)
class CameraLight(Options):
    """Light at the camera: a point light of ``intensity`` (W/sr) at a perspective camera's
    centre; for an orthographic camera a directional light along the view direction with
    irradiance ``intensity`` (W/m^2)."""

    intensity: float = option(1.0, doc="point intensity (W/sr) or irradiance (W/m^2)", ge=0)


@dataclass(frozen=True)
class FlashLight(Options):
    """A flash or flood light on the camera's rig: a point emitter at ``baseline`` metres from
    the camera's centre, in its image plane towards ``baseline_azimuth`` (0: the camera's +x,
    its image right; pi/2: its +y, image down), its beam along the camera's optical axis.

    Its radiant intensity is ``intensity cos^n(theta)`` (``theta`` from the axis, no light
    beyond ``cutoff``), so the ground receives ``I0 cos^n(theta) cos(i) / d^2``
    (:func:`simlunar.geometry.point_irradiance`: inverse-square falloff, incidence, beam).
    ``intensity`` is W/sr in the units of the sun's W/m^2: a flash of ``Q`` J over an
    exposure of ``t`` s has ``Q (n + 1) / (2 pi t)`` (:func:`simlunar.geometry.beam_intensity`).
    It is rendered as a Mitsuba ``projector`` at the light whose texture is the beam profile
    (:func:`flash_texture`), measured against :meth:`irradiance` in ``tests/render``.
    The co-located idealisation (light at infinity on the optical axis) is :class:`CameraLight`.
    """

    intensity: float = option(1.0, doc="on-axis radiant intensity", unit="W/sr", ge=0)
    baseline: float = option(
        0.0,
        doc="distance of the light from the camera's centre in its image plane",
        unit="m",
        ge=0,
    )
    baseline_azimuth: float = option(
        0.0,
        doc="direction of the baseline in the image plane from the camera's +x towards +y",
        unit="rad",
    )
    beam_exponent: float = option(
        0.0, doc="n of the cos^n beam profile (0: isotropic within the cutoff)", ge=0, le=1000
    )
    cutoff: float = option(
        np.radians(60.0),
        doc="half-angle of the beam; no light beyond it",
        unit="rad",
        gt=0,
        lt=np.radians(85.0),
    )

    def pose(self, camera) -> tuple[np.ndarray, np.ndarray]:
        """World position of the light and its beam axis (unit) on ``camera``'s rig."""
        if not isinstance(camera, (Camera, OrthoCamera)):
            raise ValueError(f"flash: unknown camera type {type(camera).__name__}")
        offset = self.baseline * np.array(
            [np.cos(self.baseline_azimuth), np.sin(self.baseline_azimuth), 0.0]
        )
        position = camera.pose.device_to_world(offset)
        return np.asarray(position, dtype=np.float64), np.asarray(camera.pose.forward, float)

    def irradiance(self, camera, points, normals) -> np.ndarray:
        """Irradiance (W/m^2) on world ``points`` (..., 3) with ``normals`` (no occlusion)."""
        position, axis = self.pose(camera)
        return point_irradiance(
            points, normals, position=position, axis=axis, intensity=self.intensity,
            beam_exponent=self.beam_exponent, cutoff=self.cutoff,
        )  # fmt: skip


#: texels on a side of the flash's beam texture (bilinear: the profile is smooth)
FLASH_TEXTURE = 512


def flash_texture(beam_exponent: float, cutoff: float, size: int = FLASH_TEXTURE) -> np.ndarray:
    """The ``projector`` texture of a cos^n beam: float32 (size, size), field ``2 cutoff``.

    Mitsuba's ``projector`` delivers ``pi * scale * texture`` on a plane parallel to its image
    plane at depth 1 (see :class:`ProjectorLight`); a point source of intensity
    ``I0 cos^n(theta)`` gives that plane ``I0 cos^n(theta) cos^3(theta)``, so the texture is
    ``cos^(n+3)(theta)`` (0 beyond the cutoff) and the scale ``I0 / pi``.
    """
    t = np.tan(cutoff)
    x = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    r2 = (x[None, :] ** 2 + x[:, None] ** 2) * t * t
    cos_t = 1.0 / np.sqrt(1.0 + r2)
    tex = np.where(cos_t >= np.cos(cutoff), cos_t ** (beam_exponent + 3.0), 0.0)
    return np.ascontiguousarray(tex, dtype=np.float32)


@dataclass(frozen=True, eq=False)
class ProjectorLight:
    """Pinhole projector (Mitsuba ``projector`` emitter) showing a pattern.

    Parameters
    ----------
    projector : geometry.Projector
        Pose and (centred, square-pixel) intrinsics; the pattern resolution is
        ``(intrinsics.height, intrinsics.width)``.
    pattern : (h, w) array
        Relative irradiance per projector pixel, usually in [0, 1]; row 0 is the top row,
        column 0 the left column of the projector image (same convention as a camera).
    scale : float
        Irradiance (W/m^2) per unit pattern value on a plane parallel to the projector's
        image plane at depth 1 m; at depth z it is ``scale * pattern / z^2`` (no cos^3
        fall-off on such a plane). Mitsuba's ``projector`` delivers ``pi * scale`` there
        (measured, ``tests/render/test_lights.py``), so its ``scale`` is ours / pi.
    supersample : int
        1: the pattern is one value per projector pixel, shown as a pixel grid (nearest
        texture filter). S > 1: the pattern is the emitted image sampled S x S times per
        projector pixel ((S h, S w), :func:`simlunar.imaging.projector_optics.emit`), shown
        bilinearly interpolated between its samples.
    """

    projector: Projector
    pattern: np.ndarray
    scale: float = 1.0
    supersample: int = 1

    @property
    def pattern_shape(self) -> tuple[int, int]:
        """(rows, cols) of the pattern: the projector's, times ``supersample``."""
        h, w = self.projector.intrinsics.shape
        return (h * self.supersample, w * self.supersample)

    def __post_init__(self) -> None:
        if not isinstance(self.projector, Projector):
            raise ValueError(
                f"projector must be a geometry.Projector, got {type(self.projector).__name__}"
            )
        if int(self.supersample) != self.supersample or self.supersample < 1:
            raise ValueError(f"supersample must be a whole number >= 1, got {self.supersample}")
        p = check_pattern(self.pattern, self.pattern_shape)
        object.__setattr__(self, "pattern", p)
        if not (np.isfinite(self.scale) and self.scale >= 0):
            raise ValueError(f"projector scale must be >= 0, got {self.scale}")


@dataclass(frozen=True)
class AmbientLight(Options):
    """Constant environment radiance (off unless added to the light list)."""

    radiance: float = option(doc="radiance of the environment", ge=0)


LIGHTS = {
    "sun": SunLight,
    "camera": CameraLight,
    "flash": FlashLight,
    "projector": ProjectorLight,
    "ambient": AmbientLight,
}


def make_light(name: str, **kw):
    """Build a light spec by registry name (``sun``, ``camera``, ``projector``, ``ambient``)."""
    try:
        cls = LIGHTS[name]
    except KeyError:
        raise ValueError(f"unknown light {name!r}; valid: {', '.join(sorted(LIGHTS))}") from None
    return cls(**kw)


def sun_direction(elevation: float, azimuth: float) -> np.ndarray:
    """Unit vector towards a sun at ``elevation`` and ``azimuth`` (rad, from +y clockwise)."""
    ce = np.cos(elevation)
    return np.array([np.sin(azimuth) * ce, np.cos(azimuth) * ce, np.sin(elevation)])


def check_pattern(pattern, shape: tuple[int, int]) -> np.ndarray:
    """Validate a projector pattern: finite, >= 0, of ``shape`` (h, w). Returns float32 copy."""
    p = np.array(pattern, dtype=np.float32, copy=True)
    if p.shape != tuple(shape):
        raise ValueError(f"pattern shape {p.shape} does not match the projector's {tuple(shape)}")
    if not np.all(np.isfinite(p)) or np.any(p < 0):
        raise ValueError("pattern values must be finite and >= 0")
    p.setflags(write=False)
    return p


PROJECTOR_ID = "projector"


def _camera_light_dict(mi, light: CameraLight, camera) -> dict:
    """A light at the camera: directional along an orthographic camera's axis, else a point."""
    value = {"type": "uniform", "value": float(light.intensity)}
    if isinstance(camera, OrthoCamera):
        return {
            "type": "directional",
            "direction": mi.ScalarVector3f(camera.pose.forward),
            "irradiance": value,
        }
    if isinstance(camera, Camera):
        return {
            "type": "point",
            "position": mi.ScalarPoint3f(camera.pose.position),
            "intensity": value,
        }
    raise ValueError(f"camera: unknown camera type {type(camera).__name__}")


def emitter_dicts(light, camera, *, index: int = 0) -> dict[str, dict]:
    """Mitsuba emitter dictionaries (keyed by scene id) for one light spec.

    Parameters
    ----------
    light : SunLight, CameraLight, ProjectorLight or AmbientLight
    camera : geometry.Camera or geometry.OrthoCamera
        The rendering camera (used by :class:`CameraLight`).
    index : int
        Position of the light in the scene's list (keeps ids unique).
    """

    mi = backend.mitsuba()
    if isinstance(light, SunLight):
        dirs, irr = light.directions()
        return {
            f"sun{index}_{k}": {
                "type": "directional",
                "direction": mi.ScalarVector3f(-d),  # propagation direction
                "irradiance": {"type": "uniform", "value": float(e)},
            }
            for k, (d, e) in enumerate(zip(dirs, irr))
        }
    if isinstance(light, CameraLight):
        return {f"camlight{index}": _camera_light_dict(mi, light, camera)}
    if isinstance(light, FlashLight):
        position, axis = light.pose(camera)
        up = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
        to_world = mi.ScalarTransform4f().look_at(
            origin=mi.ScalarPoint3f(position),
            target=mi.ScalarPoint3f(position + axis),
            up=mi.ScalarVector3f(up),
        )
        tex = flash_texture(light.beam_exponent, light.cutoff)
        return {
            f"flash{index}": {
                "type": "projector",
                "fov": float(np.degrees(2.0 * light.cutoff)),
                "to_world": to_world,
                "scale": float(light.intensity) / np.pi,
                "irradiance": {
                    "type": "bitmap",
                    "data": mi.TensorXf(tex[..., None]),
                    "filter_type": "bilinear",
                    "raw": True,
                    "wrap_mode": "clamp",
                },
            }
        }
    if isinstance(light, ProjectorLight):
        k = light.projector.intrinsics
        return {
            PROJECTOR_ID if index == 0 else f"{PROJECTOR_ID}{index}": {
                "type": "projector",
                "fov": k.fov_x_deg,
                "to_world": mi.ScalarTransform4f(to_world_matrix(light.projector.pose)),
                "scale": float(light.scale) / np.pi,  # Mitsuba's texture value 1 gives E = pi
                "irradiance": {
                    "type": "bitmap",
                    "data": mi.TensorXf(np.ascontiguousarray(light.pattern[..., None])),
                    "filter_type": "nearest" if light.supersample == 1 else "bilinear",
                    "raw": True,
                    "wrap_mode": "clamp",
                },
            }
        }
    if isinstance(light, AmbientLight):
        return {
            f"ambient{index}": {
                "type": "constant",
                "radiance": {"type": "uniform", "value": float(light.radiance)},
            }
        }
    raise ValueError(
        f"lights: unknown light spec {type(light).__name__}; valid: "
        f"{', '.join(c.__name__ for c in LIGHTS.values())}"
    )
