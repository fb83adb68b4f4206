"""Scene YAML model and `simlunar render` (outputs, ground truth, bad input -> exit 2)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.config import translate
from simlunar.config.render import RenderCfg
from simlunar.config.scene import SceneCfg, load_scene
from simlunar.errors import ConfigError
from simlunar.geometry import Camera, OrthoCamera
from simlunar.render.lights import CameraLight, SunLight
from simlunar.terrain.types import Terrain

REPO = Path(__file__).resolve().parents[2]


def _dem(tmp_path, shape=(12, 16)):
    from simlunar.terrain.io import save_dem

    y, x = np.mgrid[0 : shape[0], 0 : shape[1]]
    h = 0.3 * np.sin(x / 3.0) * np.cos(y / 4.0)
    t = Terrain(h, np.full(shape, 0.2, np.float32), 0.5)
    save_dem(tmp_path / "dem.npz", t)
    return t


def _write(tmp_path, data, name="scene.yaml"):
    p = tmp_path / name
    p.write_text(yaml.safe_dump(data))
    return p


RENDER = {
    "camera": {"kind": "orthographic_nadir", "altitude_m": 10},
    "light": {"kind": "sun", "elevation_deg": 40, "azimuth_deg": 90},
    "bsdf": {"kind": "lambert"},
    "spp": 2,
    "max_depth": 2,
    "sensor": None,
}
BASE = {"name": "tiny", "terrain": {"file": "dem.npz", "spacing_m": 0.5}, "render": RENDER}


def _scene(**render) -> dict:
    """BASE with keys of its render section replaced."""
    return {**BASE, "render": {**RENDER, **render}}


def test_quickstart_scene_validates():
    cfg = load_scene(REPO / "scenes" / "quickstart_scene.yaml")
    assert cfg.terrain.preset == "aerial_1"
    assert cfg.render.light.angular_diameter == pytest.approx(np.radians(0.53))
    assert cfg.render.bsdf.kind == "oren_nayar"


def test_scene_defaults_and_units():
    cfg = SceneCfg.model_validate(
        {"terrain": {"preset": "aerial_1"}, "render": {"light": {"elevation_deg": "0.5 rad"}}}
    )
    r = cfg.render
    assert r.camera.kind == "orthographic_nadir"
    assert r.light.kind == "sun"
    assert r.light.elevation == pytest.approx(0.5)
    # the experiment's render defaults, bounds included: one model for both
    assert r == RenderCfg.model_validate({"light": {"elevation_deg": "0.5 rad"}})


def test_build_camera_from_intrinsics_and_lights():
    t = Terrain(np.zeros((4, 6)), np.zeros((4, 6), np.float32), 1.0)
    cfg = SceneCfg.model_validate(
        {
            "terrain": {"preset": "aerial_1"},
            "render": {
                "camera": {
                    "kind": "perspective",
                    "width": 40,
                    "height": 30,
                    "fx": 50,
                    "fy": 50,
                    "cx": 21.5,
                    "cy": 14.0,
                    "position_m": [0, 0, 10],
                    "look_at_m": [1, 0, 0],
                },
                "light": {"kind": "camera", "intensity": 3.0},
                "ambient_radiance": 0.1,
            },
        }
    )
    cam = translate.camera(cfg.render.camera, t)
    assert isinstance(cam, Camera)
    assert (cam.intrinsics.cx, cam.intrinsics.cy, cam.intrinsics.width) == (21.5, 14.0, 40)
    np.testing.assert_allclose(cam.position, [0, 0, 10])
    lights = translate.lights(cfg.render.light, cfg.render.ambient_radiance)
    assert isinstance(lights[0], CameraLight) and lights[0].intensity == 3.0
    assert lights[1].radiance == 0.1
    plain = SceneCfg.model_validate({"terrain": {"preset": "aerial_1"}})
    ortho = translate.camera(plain.render.camera, t)
    assert isinstance(ortho, OrthoCamera) and ortho.shape == (4, 6)


def test_sun_with_disk():
    cfg = SceneCfg.model_validate(
        {
            "terrain": {"preset": "aerial_1"},
            "render": {"light": {"angular_diameter_deg": 0.53, "irradiance": 2}},
        }
    )
    (sun,) = translate.lights(cfg.render.light, cfg.render.ambient_radiance)
    assert isinstance(sun, SunLight) and sun.irradiance == 2.0
    assert sun.angular_diameter == pytest.approx(np.radians(0.53))


@pytest.mark.render
def test_cli_render_writes_outputs(tmp_path):
    from simlunar.imaging.exr import read_exr

    t = _dem(tmp_path)
    scene = _write(tmp_path, BASE)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["render", str(scene), "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert str(out / "radiance.exr") in res.output and "preview.png" in res.output
    names = sorted(p.name for p in out.iterdir())
    assert names == [
        "ground_truth.exr",
        "ground_truth.npz",
        "preview.png",
        "radiance.exr",
        "scene.json",
    ]  # and no temporary files left behind
    rad = read_exr(out / "radiance.exr")
    assert set(rad) >= {"R", "G", "B"} and rad["R"].shape == (12, 16)
    assert rad["R"][1:-1, 1:-1].min() > 0
    with np.load(out / "ground_truth.npz") as npz:
        gt = dict(npz)
    assert gt["valid"].all()
    # the nadir camera's depth is altitude minus the DEM, cell for cell
    np.testing.assert_allclose(gt["depth"], 10.0 - t.heights, atol=1e-5)
    exr = read_exr(out / "ground_truth.exr")
    np.testing.assert_allclose(exr["depth"], gt["depth"], atol=1e-5)
    np.testing.assert_allclose(exr["position.Z"], t.heights, atol=1e-5)


@pytest.mark.render
def test_cli_render_with_sensor(tmp_path):
    _dem(tmp_path)
    scene = _write(tmp_path, _scene(sensor={"bits": 8}))
    res = CliRunner().invoke(app, ["render", str(scene), "--out", str(tmp_path / "o")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "o" / "sensor.png").is_file()


@pytest.mark.parametrize(
    ("patch", "needle"),
    [
        ({"camera": {"kind": "fisheye"}}, "render.camera"),
        ({"spp": -1}, "render.spp"),
        ({"spp": 0}, "render.spp"),
        ({"spp": 5000}, "render.spp"),
        ({"light": {"kind": "laser"}}, "render.light"),
        ({"bsdf": {"kind": "phong"}}, "render.bsdf"),
        ({"bsdf": {"kind": "oren_nayar", "sigma_deg": 120}}, "render.bsdf.sigma_deg"),
        ({"light": {"kind": "sun", "elevation_deg": 100}}, "elevation_deg"),
        ({"colour": "grey"}, "render.colour"),
        (
            {
                "camera": {
                    "kind": "perspective",
                    "width": 8,
                    "height": 8,
                    "fov_deg": 40,
                    "fx": 5,
                    "position_m": [0, 0, 1],
                    "look_at_m": [0, 0, 0],
                }
            },
            "fov_deg or fx",
        ),
    ],
)
def test_bad_scene_is_one_line_exit_2(tmp_path, patch, needle):
    _dem(tmp_path)
    scene = _write(tmp_path, _scene(**patch))
    res = CliRunner().invoke(app, ["render", str(scene), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2, res.output
    assert "Traceback" not in res.output
    err = res.stderr if hasattr(res, "stderr") else res.output
    assert err.startswith("error: ") and needle in err
    assert not (tmp_path / "o").exists()


def test_missing_dem_names_the_file(tmp_path):
    scene = _write(tmp_path, BASE)  # no dem.npz written
    res = CliRunner().invoke(app, ["render", str(scene), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert "terrain.file: file not found" in res.output and "dem.npz" in res.output


def test_missing_scene_file_and_bad_yaml(tmp_path):
    with pytest.raises(FileNotFoundError, match="scene file not found"):
        load_scene(tmp_path / "none.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("terrain: [unclosed")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_scene(bad)
