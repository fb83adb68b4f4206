"""The rover_mast camera in experiment configs: validation, the built camera, sweep labels."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from simlunar.config.loading import load_experiment, validate_data
from simlunar.errors import ConfigError
from simlunar.pipeline.runner import expand
from simlunar.pipeline.unit import scene_inputs
from simlunar.results.records import unit_label

ROOT = Path(__file__).resolve().parents[2]


def _data(camera):
    return {
        "name": "vp",
        "seed": 1,
        "terrain": {"preset": "aerial_3", "scale": 0.05},
        "render": {"camera": camera},
        "study": {"kind": "sampling", "densities": [0.1], "trials": 1},
    }


def test_rover_mast_builds_a_camera_at_mast_height_over_the_ground():
    cfg = validate_data(
        _data({"kind": "rover_mast", "height_m": "150 cm", "depression_deg": 60, "azimuth_deg": 90})
    )
    terrain, cam, _, _ = scene_inputs(cfg)
    x0, x1, y0, y1 = terrain.extent
    np.testing.assert_allclose(cam.position[:2], [(x0 + x1) / 2, (y0 + y1) / 2])
    rows, cols = terrain.shape
    r, c = rows // 2, cols // 2  # the centre lies between four cell centres
    ground = terrain.heights[r - 1 : r + 1, c - 1 : c + 1].mean()
    assert cam.position[2] == pytest.approx(ground + 1.5)
    # looking east, 60 deg down; 320 x 240 px, 60 deg horizontal field of view by default
    np.testing.assert_allclose(cam.pose.forward, [0.5, 0.0, -np.sqrt(3) / 2], atol=1e-12)
    assert cam.shape == (240, 320) and cam.intrinsics.fov_x_deg == pytest.approx(60.0)


@pytest.mark.parametrize(
    "camera, key",
    [
        ({"kind": "rover_mast", "depression_deg": 0}, "render.camera.depression_deg"),
        ({"kind": "rover_mast", "height_m": -1}, "render.camera.height_m"),
        ({"kind": "rover_mast", "tilt": 3}, "render.camera.tilt"),
    ],
)
def test_bad_rover_mast_keys_are_named(camera, key):
    with pytest.raises(ConfigError) as e:
        validate_data(_data(camera))
    assert str(e.value).startswith(f"{key}: "), str(e.value)  # the full key path


def test_site_outside_the_terrain_is_one_line():
    cfg = validate_data(_data({"kind": "rover_mast", "site_m": [1e4, 0]}))
    with pytest.raises(ValueError, match="outside"):
        scene_inputs(cfg)


def test_viewpoint_ablation_units_have_distinct_labels():
    cfg = load_experiment(ROOT / "experiments" / "ablation_viewpoint.yaml")
    labels = [unit_label(u) for u in expand(cfg)]
    assert len(set(labels)) == 3
    assert labels[1] == "camera=rover_mast(height_m=1.5, depression_deg=30)"
