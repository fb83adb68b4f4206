"""The render section of the schema, built directly: defaults, degrees to radians, the camera's
intrinsics given one way only, a thin lens with its focus, keys without effect refused."""

from __future__ import annotations

import math

import pytest
from pydantic import ValidationError

from simlunar.config.render import (
    MAX_SPP,
    CameraLightCfg,
    HapkeCfg,
    LambertCfg,
    OrenNayarCfg,
    OrthoNadirCfg,
    PerspectiveCfg,
    RenderCfg,
    RoverMastCfg,
    SensorCfg,
    SunLightCfg,
)


def _msg(cls, **kw) -> str:
    with pytest.raises(ValidationError) as info:
        cls.model_validate(kw)
    return info.value.errors()[0]["msg"]


PERSP = {"kind": "perspective", "width": 64, "height": 48, "position_m": (0, 0, 10),
         "look_at_m": (0, 0, 0)}  # fmt: skip


def test_defaults():
    r = RenderCfg()
    assert isinstance(r.camera, OrthoNadirCfg) and r.camera.altitude_m == 50.0
    assert isinstance(r.light, SunLightCfg) and r.light.elevation_deg == 30.0
    assert isinstance(r.bsdf, OrenNayarCfg) and r.bsdf.sigma_deg == 20.0
    assert isinstance(r.sensor, SensorCfg) and r.sensor.exposure_e is None
    assert (r.spp, r.max_depth, r.ambient_radiance) == (16, 3, 0.0)
    assert RenderCfg(sensor=None).sensor is None  # noiseless radiance


def test_sections_are_chosen_by_kind():
    r = RenderCfg.model_validate(
        {"camera": {"kind": "rover_mast"}, "light": {"kind": "camera", "intensity": 2},
         "bsdf": {"kind": "hapke", "w": 0.3}}
    )  # fmt: skip
    assert isinstance(r.camera, RoverMastCfg) and (r.camera.width, r.camera.height) == (320, 240)
    assert isinstance(r.light, CameraLightCfg) and r.light.intensity == 2
    assert isinstance(r.bsdf, HapkeCfg) and r.bsdf.w == 0.3 and r.bsdf.b is None
    assert isinstance(RenderCfg(bsdf={"kind": "lambert"}).bsdf, LambertCfg)
    assert "kind must be one of lambert, oren_nayar, hapke" in _msg(RenderCfg, bsdf={})


def test_angles_in_radians():
    sun = SunLightCfg(elevation_deg="0.5 rad", azimuth_deg=90, angular_diameter_deg=0.53)
    assert sun.elevation == pytest.approx(0.5)
    assert sun.azimuth == pytest.approx(math.pi / 2)
    assert sun.angular_diameter == pytest.approx(0.53 * math.pi / 180)
    assert OrenNayarCfg(kind="oren_nayar", sigma_deg=45).sigma == pytest.approx(math.pi / 4)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ({}, "give fov_deg or all of fx, fy, cx, cy"),
        ({"fx": 50, "fy": 50, "cx": 32}, "give fov_deg or all of fx, fy, cx, cy"),
        ({"fov_deg": 40, "fx": 50}, "give fov_deg or fx, fy, cx, cy, not both"),
        ({"fov_deg": 40, "aperture_radius_m": 0.01},
         "a thin lens (aperture_radius_m > 0) needs focus_distance_m"),
        ({"fov_deg": 40, "focus_distance_m": 5},
         "focus_distance_m: has no effect on a pinhole camera (aperture_radius_m 0); set "
         "aperture_radius_m > 0 for a thin lens or leave focus_distance_m null"),
        ({"fov_deg": 40, "look_at_m": (0, 0, 10)},
         "look_at_m: equals position_m (the camera looks at its own position)"),
        ({"fov_deg": 180}, "less than 180"),
    ],
)  # fmt: skip
def test_perspective_intrinsics(extra, message):
    assert message in _msg(PerspectiveCfg, **{**PERSP, **extra})


def test_perspective_forms_that_validate():
    assert PerspectiveCfg(**PERSP, fov_deg="0.5 rad").fov_deg == pytest.approx(math.degrees(0.5))
    p = PerspectiveCfg(**PERSP, fx=50, fy=50, cx=32, cy=24, aperture_radius_m="5 mm",
                       focus_distance_m=10)  # fmt: skip
    assert p.aperture_radius_m == pytest.approx(0.005) and p.up == (0.0, 0.0, 1.0)


def test_sensor_gamma_only_with_the_gamma_response():
    assert SensorCfg(response="gamma", gamma=1.8).gamma == 1.8
    assert SensorCfg(gamma=2.2).response == "linear"  # the default value is no change
    assert _msg(SensorCfg, gamma=1.8) == (
        "Value error, gamma: has no effect with response linear; set response: gamma to use it"
    )


@pytest.mark.parametrize(
    ("section", "kw", "message"),
    [
        (RenderCfg, {"spp": MAX_SPP + 1}, f"less than or equal to {MAX_SPP}"),
        (RenderCfg, {"max_depth": 1}, "greater than or equal to 2"),
        (SunLightCfg, {"elevation_deg": 0}, "greater than 0"),
        (SunLightCfg, {"azimuth_deg": 400}, "less than or equal to 360"),
        (HapkeCfg, {"kind": "hapke", "theta_bar_deg": 61}, "less than or equal to 60"),
        (OrenNayarCfg, {"kind": "oren_nayar", "sigma_deg": 90}, "less than 90"),
        (SensorCfg, {"bits": 17}, "less than or equal to 16"),
        (RoverMastCfg, {"kind": "rover_mast", "depression_deg": 0}, "greater than 0"),
    ],
)
def test_bounds(section, kw, message):
    assert message in _msg(section, **kw)
