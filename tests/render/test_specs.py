"""render.specs gathers the light and BSDF specs of their own modules, without Mitsuba."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from simlunar.render import lights, materials, specs

LIGHT_NAMES = (
    "LIGHTS",
    "SUN_ANGULAR_DIAMETER",
    "AmbientLight",
    "CameraLight",
    "ProjectorLight",
    "SunLight",
    "make_light",
)
BSDF_NAMES = ("BSDFS", "HapkeBSDF", "LambertBSDF", "OrenNayarBSDF", "make_bsdf")


def test_specs_are_the_objects_of_their_own_modules():
    for name in LIGHT_NAMES:
        assert getattr(specs, name) is getattr(lights, name), name
    for name in BSDF_NAMES:
        assert getattr(specs, name) is getattr(materials, name), name
    assert sorted(specs.__all__) == sorted(LIGHT_NAMES + BSDF_NAMES)


def test_specs_build_by_name():
    sun = specs.make_light("sun", elevation=0.5, azimuth=1.0)
    assert isinstance(sun, specs.SunLight) and sun.irradiance == 1.0
    assert isinstance(specs.make_bsdf("oren_nayar", sigma=0.3), specs.OrenNayarBSDF)
    # the sun's real apparent diameter, 0.53 deg, is the one soft shadows use
    assert math.degrees(specs.SUN_ANGULAR_DIAMETER) == pytest.approx(0.53, abs=0.01)
    with pytest.raises(ValueError, match=r"^unknown light 'moon'; valid: ambient, camera, "):
        specs.make_light("moon")
    with pytest.raises(
        ValueError,
        match=r"^unknown BSDF 'phong'; valid: lambert, oren_nayar, hapke, lunar_lambert, lroc_empirical$",
    ):
        specs.make_bsdf("phong")


def test_importing_the_specs_imports_no_renderer():
    code = (
        "import sys, simlunar.render.specs\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in "
        "('mitsuba', 'drjit', 'mitransient')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
