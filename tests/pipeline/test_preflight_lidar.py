"""Preflight of a LIDAR unit: the camera's rays and a steered beam's gate prior, before any
render (the CLI's one-line refusals are in test_bad_inputs)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.config.schema import ExperimentCfg
from simlunar.errors import ConfigError
from simlunar.pipeline.inputs import TerrainFacts
from simlunar.pipeline.preflight_lidar import check_gate_prior, grid_rays, perspective_camera

CAMERA = {"kind": "perspective", "width": 64, "height": 48, "fov_deg": 40,
          "position_m": [20.0, -12.0, 30.0], "look_at_m": [20.0, -12.0, 0.0], "up": [0, 1, 0]}  # fmt: skip
FACTS = TerrainFacts(200, 200, 0.2, (0.0, 0.0), -1.0, 1.0)


def _cfg(gate: dict, window_m: float = 8.0) -> ExperimentCfg:
    return ExperimentCfg.model_validate({
        "name": "x", "terrain": {"preset": "aerial_1", "scale": 0.125},
        "render": {"camera": CAMERA},
        "study": {"kind": "lidar", "sensor": "steered_beam", "planners": ["random"],
                  "densities": ["1/64"], "trials": 1,
                  "options": {"gate": gate, "steered_beam": {"window_m": window_m}}},
    })  # fmt: skip


def test_grid_rays_reach_the_image_corners():
    cam = perspective_camera(_cfg({}).render.camera, "render.camera")
    o, d = grid_rays(cam, most=8)
    assert d.shape == (8 * 8, 3) and np.allclose(o, [20.0, -12.0, 30.0])
    # the first and last rays pass through the image's corners (0, 0) and (64, 48)
    _, corners = cam.rays(np.array([[0.0, 0.0], [64.0, 48.0]]))
    assert np.allclose(d[[0, -1]], corners)


def test_a_gate_prior_wider_than_the_window_is_refused_and_a_narrow_one_passes():
    # 30 m up, a 40 x 31 deg view: a 20 deg slope prior about the boresight's footprint opens
    # each corner ray's window by metres; 3 deg by well under a metre
    with pytest.raises(ConfigError, match=r"window_m: 8 m cannot hold the gate prior: it needs"):
        check_gate_prior(_cfg({"max_slope_deg": 20}), FACTS)
    check_gate_prior(_cfg({"max_slope_deg": 3}), FACTS)
    check_gate_prior(_cfg({}), FACTS)  # no prior: nothing to hold
    # the same wide prior fits a wide window
    check_gate_prior(_cfg({"max_slope_deg": 20}, window_m=40.0), FACTS)


def test_the_altimeter_s_plane_is_taken_at_the_terrain_s_lowest_point():
    # with an altimeter the datum is read in the scan: the check takes the farthest plane the
    # terrain allows (its lowest point), where the slope prior's window is widest
    # (9.3 m with the plane at z = 0, 13.7 m at z = -25 m)
    cfg = _cfg({"altimeter": True, "max_slope_deg": 10}, window_m=11.0)
    high = TerrainFacts(200, 200, 0.2, (0.0, 0.0), 0.0, 1.0)
    low = TerrainFacts(200, 200, 0.2, (0.0, 0.0), -25.0, 1.0)
    check_gate_prior(cfg, high)
    with pytest.raises(ConfigError, match="cannot hold the gate prior"):
        check_gate_prior(cfg, low)
