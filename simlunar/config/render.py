"""Render sections of the schema: camera, light, BSDF, sensor and ``render``."""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import (
    AfterValidator,
    BeforeValidator,
    Discriminator,
    Field,
    Tag,
    WithJsonSchema,
    model_validator,
)

from simlunar.config.fields import (
    Deg,
    Metres,
    _Model,
    _tagged_union,
    library_values,
    options_model,
)
from simlunar.render.materials import BSDFS

__all__ = [
    "MAX_SPP",
    "BsdfCfg",
    "CameraCfg",
    "CameraLightCfg",
    "GuideFlashCfg",
    "GuideFlashFrameCfg",
    "HapkeCfg",
    "LambertCfg",
    "LightCfg",
    "OrenNayarCfg",
    "OrthoNadirCfg",
    "PerspectiveCfg",
    "RenderCfg",
    "RoverMastCfg",
    "SensorCfg",
    "SunLightCfg",
    "Vec3",
]

# --------------------------------------------------------------------------- render
#: most samples per pixel of any render (render.spp, the scanner's sparse_spp)
MAX_SPP = 4096


class OrthoNadirCfg(_Model):
    """Orthographic nadir camera whose pixel (r, c) sees DEM cell (r, c) (aerial view)."""

    kind: Literal["orthographic_nadir"] = "orthographic_nadir"
    altitude_m: Metres = Field(50.0, gt=0, description="camera height above z = 0 (m)")


Vec3 = tuple[float, float, float]


class PerspectiveCfg(_Model):
    """Pinhole (or thin-lens) camera at ``position_m`` looking at ``look_at_m``.

    Give either ``fov_deg`` (horizontal; square pixels, centred principal point) or all of
    ``fx, fy, cx, cy`` (pixels; pixel centres at i + 0.5, so centred is ``width/2``).
    """

    kind: Literal["perspective"]
    width: int = Field(gt=0, le=16384)
    height: int = Field(gt=0, le=16384)
    fov_deg: Deg | None = Field(None, gt=0, lt=180, description="horizontal field of view")
    fx: float | None = Field(None, gt=0, description="focal length (px)")
    fy: float | None = Field(None, gt=0, description="focal length (px)")
    cx: float | None = Field(None, description="principal point (px)")
    cy: float | None = Field(None, description="principal point (px)")
    position_m: Vec3
    look_at_m: Vec3
    up: Vec3 = Field((0.0, 0.0, 1.0), description="world up direction (unit-free)")
    aperture_radius_m: Metres = Field(0.0, ge=0, description="thin lens; 0 = pinhole")
    focus_distance_m: Metres | None = Field(None, gt=0)

    @model_validator(mode="after")
    def _intrinsics(self) -> PerspectiveCfg:
        k = [self.fx, self.fy, self.cx, self.cy]
        if self.fov_deg is None and any(v is None for v in k):
            raise ValueError("give fov_deg or all of fx, fy, cx, cy")
        if self.fov_deg is not None and any(v is not None for v in k):
            raise ValueError("give fov_deg or fx, fy, cx, cy, not both")
        if self.aperture_radius_m > 0 and self.focus_distance_m is None:
            raise ValueError("a thin lens (aperture_radius_m > 0) needs focus_distance_m")
        if self.aperture_radius_m == 0 and self.focus_distance_m is not None:
            raise ValueError(
                "focus_distance_m: has no effect on a pinhole camera (aperture_radius_m 0); "
                "set aperture_radius_m > 0 for a thin lens or leave focus_distance_m null"
            )
        if tuple(self.position_m) == tuple(self.look_at_m):
            raise ValueError("look_at_m: equals position_m (the camera looks at its own position)")
        return self


class RoverMastCfg(_Model):
    """Perspective camera on a rover mast: ``height_m`` above the ground at ``site_m``, its
    optical axis ``depression_deg`` below the horizon, towards ``azimuth_deg``."""

    kind: Literal["rover_mast"]
    width: int = Field(320, gt=0, le=16384)
    height: int = Field(240, gt=0, le=16384)
    fov_deg: Deg = Field(60.0, gt=0, lt=180, description="horizontal field of view")
    height_m: Metres = Field(1.5, gt=0, description="camera height above the terrain at the site")
    depression_deg: Deg = Field(
        30.0, gt=0, le=90, description="optical axis below the horizon (90 = straight down)"
    )
    azimuth_deg: Deg = Field(0.0, description="look direction from +y (north) clockwise to +x")
    site_m: tuple[float, float] | None = Field(
        None, description="world (x, y) of the mast foot; default the terrain's centre"
    )


CameraCfg = _tagged_union("orthographic_nadir", OrthoNadirCfg, PerspectiveCfg, RoverMastCfg)


class SunLightCfg(_Model):
    """A distant sun. Azimuth from +y (north) clockwise towards +x (east)."""

    kind: Literal["sun"] = "sun"
    elevation_deg: Deg = Field(30.0, gt=0, le=90, description="above the horizon (0 < e <= 90)")
    azimuth_deg: Deg = Field(135.0, ge=-360, le=360)
    irradiance: float = Field(
        1.0,
        gt=0,
        le=1e6,
        description="W/m^2 at normal incidence (relative; at most 1e6, a sun that drowns any "
        "projector pattern and overflows the sensor model's photon counts)",
    )
    angular_diameter_deg: Deg = Field(
        0.0, ge=0, lt=90, description="solar disk; 0.53 = the real sun (soft shadow edges)"
    )

    @property
    def elevation(self) -> float:
        return math.radians(self.elevation_deg)

    @property
    def azimuth(self) -> float:
        return math.radians(self.azimuth_deg)

    @property
    def angular_diameter(self) -> float:
        return math.radians(self.angular_diameter_deg)


class CameraLightCfg(_Model):
    """A point light at the camera's centre (no visible shadows)."""

    kind: Literal["camera"]
    intensity: float = Field(1.0, gt=0)


LightCfg = _tagged_union("sun", SunLightCfg, CameraLightCfg)


class GuideSunCfg(_Model):
    """A further sun of a guide frame (the same camera, terrain and sensor model)."""

    elevation_deg: Deg = Field(gt=0, le=90, description="above the horizon (0 < e <= 90)")
    azimuth_deg: Deg = Field(ge=-360, le=360, description="from +y (north) clockwise to +x")
    irradiance: float = Field(1.0, gt=0, description="W/m^2 at normal incidence (relative)")


class GuideSunFrameCfg(_Model):
    """``{sun: {elevation_deg: .., azimuth_deg: ..}}``: a guide frame under another sun."""

    sun: GuideSunCfg


class GuideFlashCfg(_Model):
    """A flash on the camera's rig (:class:`simlunar.render.lights.FlashLight`): a point
    emitter ``baseline_m`` from the camera in its image plane, beam ``cos^n`` along the optical
    axis, inverse-square falloff. Its output is one of ``intensity_w_sr`` (on-axis W/sr, in the
    units of the sun's W/m^2), ``energy_j`` with ``exposure_s`` (``I0 = Q (n + 1) / (2 pi t)``)
    or ``sun_ratio`` (its irradiance on the ground z = 0 straight below it, over the guide
    sun's on the same ground, ``irradiance sin(elevation)``)."""

    baseline_m: Metres = Field(0.0, ge=0, description="distance from the camera's centre")
    baseline_azimuth_deg: Deg = Field(
        0.0, ge=-360, le=360, description="baseline direction from the image's +x towards +y"
    )
    intensity_w_sr: float | None = Field(None, gt=0, description="on-axis radiant intensity")
    energy_j: float | None = Field(None, gt=0, description="energy per flash (with exposure_s)")
    exposure_s: float | None = Field(None, gt=0, description="exposure the flash fills (s)")
    sun_ratio: float | None = Field(
        None, gt=0, le=1e6, description="irradiance below the flash over the sun's (flat ground)"
    )
    beam_exponent: float = Field(0.0, ge=0, le=1000, description="n of the cos^n beam")
    cutoff_deg: Deg = Field(60.0, gt=0, lt=85, description="half-angle of the beam")
    daylight: bool = Field(
        False,
        description="true: the sun stays up, and the frame is flash-on minus flash-off (two "
        "exposures at the brighter frame's exposure); false: night or shadow, the flash alone",
    )
    flat_field: bool = Field(
        True,
        description="the reconstructions divide the frame by its falloff, incidence and beam, "
        "computed from the rig's pose and the samples' linear surface",
    )

    @model_validator(mode="after")
    def _one_output(self) -> GuideFlashCfg:
        given = [k for k in ("intensity_w_sr", "energy_j", "sun_ratio") if getattr(self, k)]
        if len(given) != 1:
            raise ValueError(
                "give the flash's output as one of intensity_w_sr, energy_j (with exposure_s) "
                f"or sun_ratio, got {', '.join(given) or 'none'}"
            )
        if (self.energy_j is None) != (self.exposure_s is None):
            raise ValueError("energy_j and exposure_s go together")
        return self


class GuideFlashFrameCfg(_Model):
    """``{flash: {baseline_m: .., sun_ratio: .., daylight: ..}}``: a guide frame under a flash
    on the camera's rig (the real co-located frame; ``camera`` is its idealisation)."""

    flash: GuideFlashCfg


def _ideal_is_camera(value):
    """``ideal`` is another spelling of ``camera``: the co-located light's limiting case."""
    return "camera" if value == "ideal" else value


def _frame_tag(v) -> str:
    """Which guide frame a value is: a name (``camera``), a flash or another sun, so a bad
    sun or flash is reported as its own key (``sun.elevation_deg``), not as "should be
    'camera'"."""
    if isinstance(v, str):
        return "camera"
    if isinstance(v, GuideFlashFrameCfg) or (isinstance(v, dict) and "flash" in v):
        return "flash"
    return "sun"


#: an extra guide frame: ``camera`` or ``ideal`` (the ideal co-located light: at infinity on
#: the optical axis, nearly pure albedo), a flash on the rig, or another sun
GuideFrameCfg = Annotated[
    Annotated[
        Annotated[
            Literal["camera"],
            Tag("camera"),
            # the editor schema takes both spellings, as the loader does
            WithJsonSchema({"type": "string", "enum": ["camera", "ideal"]}),
        ]
        | Annotated[GuideSunFrameCfg, Tag("sun")]
        | Annotated[GuideFlashFrameCfg, Tag("flash")],
        Discriminator(_frame_tag),
    ],
    BeforeValidator(_ideal_is_camera),
]


def _unique_frames(frames: list) -> list:
    seen = [f if isinstance(f, str) else f.model_dump_json() for f in frames]
    if len(set(seen)) != len(seen):
        raise ValueError("guide_frames: a frame is listed twice")
    colocated = [f for f in frames if f == "camera" or isinstance(f, GuideFlashFrameCfg)]
    if len(colocated) > 1:
        raise ValueError(
            "guide_frames: at most one co-located frame (camera, the ideal one, or a flash)"
        )
    return frames


class _BsdfCfg(_Model):
    """A BSDF block: ``kind`` names an entry of :data:`simlunar.render.materials.BSDFS`."""

    def library_values(self) -> dict:
        """Keywords of the BSDF's spec (angles in radians; unset keys: library defaults)."""
        return library_values(self)


class LambertCfg(_BsdfCfg):
    kind: Literal["lambert"]


class OrenNayarCfg(_BsdfCfg):
    """Oren-Nayar (1994); ``sigma_deg`` is the slope standard deviation."""

    kind: Literal["oren_nayar"]
    sigma_deg: Deg = Field(20.0, ge=0, lt=90, description="slope standard deviation (< 90)")
    model: Literal["full", "qualitative"] = "full"

    @property
    def sigma(self) -> float:
        return math.radians(self.sigma_deg)


class HapkeCfg(_BsdfCfg):
    """Hapke; unset parameters take the render package's lunar defaults."""

    kind: Literal["hapke"]
    w: float | None = Field(None, gt=0, le=1, description="single-scattering albedo")
    b: float | None = Field(None, ge=0, le=1)
    c: float | None = Field(None, ge=-1, le=1)
    B0: float | None = Field(
        None, ge=0, description="shadow-hiding opposition surge amplitude B_S0"
    )
    h: float | None = Field(None, gt=0, description="shadow-hiding opposition surge width h_S")
    theta_bar_deg: Deg | None = Field(None, ge=0, le=60)
    B_C0: float | None = Field(
        None, ge=0, description="coherent-backscatter opposition surge amplitude (0: none)"
    )
    h_C: float | None = Field(None, gt=0, description="coherent-backscatter opposition surge width")


#: BSDFs with a hand-written block (their YAML defaults differ from the specs' on purpose:
#: Oren-Nayar 20 deg, Hapke's unset keys = the library's lunar values)
_WRITTEN = {"lambert": LambertCfg, "oren_nayar": OrenNayarCfg, "hapke": HapkeCfg}
#: every other registered BSDF: its block derived from its spec's fields
_DERIVED = tuple(
    options_model(
        e.target,
        "".join(w.capitalize() for w in n.split("_")) + "Cfg",
        f"{e.meta.get('label', n)} (:data:`simlunar.render.materials.BSDFS`).",
        base=_BsdfCfg,
        extra={"kind": (Literal[n], ...)},
    )
    for n, e in BSDFS.items()
    if n not in _WRITTEN
)
BsdfCfg = _tagged_union(None, *_WRITTEN.values(), *_DERIVED)


class SensorCfg(_Model):
    """Camera sensor (:class:`simlunar.imaging.sensor.SensorModel`): shot noise, read noise, ADC."""

    full_well_e: float = Field(20000.0, gt=0, description="saturation capacity (electrons)")
    read_noise_e: float = Field(5.0, ge=0, description="read noise std (electrons)")
    bits: int = Field(12, ge=1, le=16, description="ADC resolution")
    exposure_e: float | None = Field(
        None,
        gt=0,
        description="electrons per unit linear radiance; null = auto exposure: the 99.5th "
        "percentile of the reference radiance fills 80% of the full well (the guide image; "
        "the white calibration frame in scanner studies)",
    )
    response: Literal["linear", "gamma"] = "linear"
    gamma: float = Field(2.2, gt=0, description="exponent of response gamma")

    @model_validator(mode="after")
    def _gamma_used(self) -> SensorCfg:
        if self.response == "linear" and self.gamma != type(self).model_fields["gamma"].default:
            raise ValueError(
                "gamma: has no effect with response linear; set response: gamma to use it"
            )
        return self


class RenderCfg(_Model):
    camera: CameraCfg = Field(default_factory=OrthoNadirCfg)
    light: LightCfg = Field(default_factory=SunLightCfg)
    bsdf: BsdfCfg = Field(default_factory=lambda: OrenNayarCfg(kind="oren_nayar"))
    ambient_radiance: float = Field(0.0, ge=0, description="constant sky radiance (0 = off)")
    spp: int = Field(16, ge=1, le=MAX_SPP)
    max_depth: int = Field(3, ge=2, le=16, description="path depth (2 = direct light only)")
    guide_frames: Annotated[list[GuideFrameCfg], AfterValidator(_unique_frames)] = Field(
        default_factory=list,
        description="extra frames of the guide view for the guided reconstructions (sampling, "
        "scanner and LIDAR studies): camera (the ideal co-located light: at infinity on the "
        "optical axis, the albedo frame; in a scanner study the projector's flood frame), "
        "{flash: {baseline_m, sun_ratio, beam_exponent, daylight, ...}} (a real flash on the "
        "rig) or {sun: {elevation_deg, azimuth_deg}}; each is one more exposure through the "
        "same sensor (two for a daylight flash: flash-on and flash-off)",
    )
    sensor: SensorCfg | None = Field(
        default_factory=SensorCfg, description="null = use noiseless radiance"
    )

    @model_validator(mode="after")
    def _guide_frames_differ_from_the_light(self):
        if isinstance(self.light, CameraLightCfg) and "camera" in self.guide_frames:
            raise ValueError(
                "guide_frames: camera is the guide view's own light (render.light) already"
            )
        for f in self.guide_frames:
            if isinstance(f, GuideFlashFrameCfg) and not isinstance(self.light, SunLightCfg):
                if f.flash.daylight or f.flash.sun_ratio is not None:
                    raise ValueError(
                        "guide_frames: a flash's daylight and sun_ratio need a sun as render.light"
                    )
        return self
