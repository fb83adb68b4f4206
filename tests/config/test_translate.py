"""Config models into library objects, unit by unit: preset keys without their ``_m`` suffix,
the diffusivity renamed; overrides validated with their key; a DEM file with its albedo; the
nadir camera over the grid; radians; the Hapke keys the YAML sets; the auto exposure."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from simlunar.config import translate
from simlunar.config.planners import FeatureOptsCfg
from simlunar.config.render import (
    CameraLightCfg,
    HapkeCfg,
    OrthoNadirCfg,
    RenderCfg,
    SensorCfg,
    SunLightCfg,
)
from simlunar.config.terrain import SCENES, PresetError, TerrainCfg, merged_preset
from simlunar.geometry import OrthoCamera
from simlunar.imaging.exposure import AUTO_EXPOSURE_LEVEL
from simlunar.render.lights import AmbientLight, CameraLight, SunLight
from simlunar.terrain.types import Terrain


def test_preset_keys_become_the_terrain_parameters():
    data = yaml.safe_load((SCENES / "aerial_1.yaml").read_text())
    p = translate.terrain_params(merged_preset("aerial_1"))
    assert (p.rows, p.cols, p.spacing) == (1000, 1600, data["grid"]["spacing_m"])
    assert p.fractal.rms == data["fractal"]["rms_m"] and p.fractal.hurst == data["fractal"]["hurst"]
    assert p.craters.diffusivity == data["craters"]["diffusivity_m2_per_myr"]
    assert p.craters.d_max == data["craters"]["d_max_m"] and p.name == "aerial_1"
    q = translate.terrain_params(merged_preset("aerial_1"), scale=0.1)
    assert (q.rows, q.cols, q.spacing) == (100, 160, p.spacing)


def test_preset_params_with_overrides():
    p = translate.preset_params("aerial_1", overrides={"fractal": {"rms_m": "5 cm"}}, scale=0.05)
    assert p.fractal.rms == pytest.approx(0.05) and p.rows == 50
    with pytest.raises(PresetError) as info:
        translate.preset_params("aerial_1", overrides={"fractal": {"rms": 1}})
    assert info.value.key == "fractal.rms" and info.value.problem.startswith("unknown key")


def test_a_dem_file_with_its_albedo_or_a_constant_one(tmp_path):
    heights = np.arange(16.0 * 16).reshape(16, 16)
    np.save(tmp_path / "dem.npy", heights)
    t = translate.build_terrain(TerrainCfg(file=str(tmp_path / "dem.npy"), spacing_m=0.5), rng=0)
    np.testing.assert_array_equal(t.heights, heights)
    assert t.spacing == 0.5
    c = translate.build_terrain(
        TerrainCfg(file=str(tmp_path / "dem.npy"), spacing_m=0.5, albedo=0.2), rng=0
    )
    np.testing.assert_allclose(c.albedo, 0.2)
    g = translate.build_terrain(TerrainCfg(preset="aerial_1", scale=0.02), rng=3)
    assert g.shape == (20, 32)
    again = translate.build_terrain(TerrainCfg(preset="aerial_1", scale=0.02), rng=3)
    np.testing.assert_array_equal(g.heights, again.heights)  # seeded


def test_the_nadir_camera_sees_cell_r_c_at_pixel_r_c():
    t = Terrain(np.zeros((4, 6)), np.ones((4, 6)), 0.5, origin=(10.0, 20.0))
    cam = translate.camera(OrthoNadirCfg(altitude_m=30), t)
    assert isinstance(cam, OrthoCamera)
    x, y = t.cell_centers()
    uv, depth = cam.project(np.array([x[5], y[3], 0.0]))
    np.testing.assert_allclose(uv, [5.5, 3.5], atol=1e-9)  # pixel centres at i + 0.5
    assert depth == pytest.approx(30.0)


def test_lights_in_radians_with_the_ambient_term():
    sun, amb = translate.lights(
        SunLightCfg(elevation_deg=30, azimuth_deg=90, angular_diameter_deg=0.5), 0.1
    )
    assert isinstance(sun, SunLight) and isinstance(amb, AmbientLight)
    assert sun.elevation == pytest.approx(math.pi / 6) and sun.azimuth == pytest.approx(math.pi / 2)
    assert sun.angular_diameter == pytest.approx(math.radians(0.5))
    (lamp,) = translate.lights(CameraLightCfg(kind="camera", intensity=3), 0.0)
    assert isinstance(lamp, CameraLight) and lamp.intensity == 3


def test_bsdfs_take_only_the_keys_the_yaml_sets():
    default = translate.bsdf(HapkeCfg(kind="hapke"))
    h = translate.bsdf(HapkeCfg(kind="hapke", w=0.3, theta_bar_deg=20))
    assert h.w == 0.3 and h.theta_bar == pytest.approx(math.radians(20))
    assert (h.b, h.c, h.B0, h.h) == (default.b, default.c, default.B0, default.h)  # lunar defaults
    on = translate.bsdf(RenderCfg().bsdf)
    assert on.sigma == pytest.approx(math.radians(20))
    # Hapke's coherent-backscatter surge reaches the spec from the YAML; unset, it is off
    assert (default.B_C0, default.h_C) == (0.0, 0.03)
    cb = translate.bsdf(HapkeCfg(kind="hapke", B_C0=0.5, h_C=0.01, B0=0.8, h=0.05))
    assert (cb.B_C0, cb.h_C, cb.B0, cb.h) == (0.5, 0.01, 0.8, 0.05)
    with pytest.raises(ValueError, match="greater than 0"):
        HapkeCfg(kind="hapke", h_C=0.0)


def test_sensor_exposure_fixed_or_automatic():
    fixed = translate.sensor_model(SensorCfg(exposure_e=500.0))
    assert fixed.exposure == 500.0 and fixed.bits == 12
    ref = np.linspace(0.0, 2.0, 1001)
    auto = translate.sensor_model(SensorCfg(full_well_e=10_000), reference=ref)
    # the 99.5th percentile of 0..2 is 1.99: it fills AUTO_EXPOSURE_LEVEL of the full well
    assert auto.exposure == pytest.approx(AUTO_EXPOSURE_LEVEL * 10_000 / 1.99)
    assert translate.sensor_model(SensorCfg()).exposure == 1.0  # no reference: a placeholder


def test_feature_options_of_each_map():
    fo = FeatureOptsCfg(levels=2, size=5)
    assert translate.feature_opts("wavelet", fo) == {
        "wavelet": "db2",
        "levels": 2,
        "boundary": "symmetric",
    }
    assert translate.feature_opts("gradient", fo) == {}
    assert translate.feature_opts("combination", fo, ["entropy", "gradient"]) == {
        "entropy": {"size": 5, "scale": "minmax"},
        "gradient": {},
    }
