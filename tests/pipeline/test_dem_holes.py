"""A GeoTIFF DEM with NaN holes within the documented share (``MAX_NAN_FRACTION``, 5 %) flows
through every study kind, every stage and every figure: the run ends, its scores are finite,
and the sampling study's figures (the sparse-mesh render among them) are drawn."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
import yaml
from scipy import ndimage
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.pipeline.inputs import MAX_NAN_FRACTION
from simlunar.terrain.io import save_dem
from simlunar.terrain.types import Terrain

PERSPECTIVE = {"kind": "perspective", "width": 48, "height": 32, "fov_deg": 40,
               "position_m": [6.0, -4.0, 15.0], "look_at_m": [6.0, -4.2, 0.0]}  # fmt: skip
STUDIES = {
    "sampling": ({}, {"strategies": ["random", "wavelet", "wavelet_lloyd"], "densities": ["1/16"],
                      "trials": 1, "metrics": ["mse", "grad"],
                      "reconstructions": ["linear", "shading", "photoclinometry"]}),
    "scanner": ({}, {"kind": "scanner", "modes": ["gray_code", "ambiguity_enhancement"],
                     "planners": ["random"], "budget": 0.1, "trials": 1,
                     "projector_px": [64, 48], "camera_px": [64, 48]}),
    "lidar": ({"camera": PERSPECTIVE}, {"kind": "lidar", "planners": ["random"],
                                        "densities": ["1/16"], "trials": 1,
                                        "reconstructions": ["linear", "shading"]}),
}  # fmt: skip


def _dem(path, hole) -> float:
    """A 40 x 60 GeoTIFF DEM (0.2 m cells) with NaN heights at ``hole``; its NaN share."""
    r = np.random.default_rng(0)
    h = ndimage.gaussian_filter(r.standard_normal((40, 60)), 3) * 2
    h[hole] = np.nan
    save_dem(path, Terrain(h, np.full(h.shape, 0.15, np.float32), 0.2, (0.0, 0.0)))
    return float(np.isnan(h).mean())


CORNER, MIDDLE = np.s_[0:5, 0:6], np.s_[10:16, 20:25]


@pytest.mark.parametrize(
    ("kind", "hole"),
    [("sampling", CORNER), ("sampling", MIDDLE), ("scanner", CORNER), ("lidar", CORNER)],
    ids=["sampling-corner", "sampling-middle", "scanner-corner", "lidar-corner"],
)
def test_each_study_kind_runs_on_a_dem_with_holes(kind, hole, tmp_path, monkeypatch):
    share = _dem(tmp_path / "dem.tif", hole)
    assert 0.01 < share < MAX_NAN_FRACTION  # 1.25 %, as the newcomer's DEM
    render, study = STUDIES[kind]
    exp = tmp_path / "exp.yaml"
    exp.write_text(yaml.safe_dump({"name": f"holes_{kind}", "seed": 1,
                                   "terrain": {"file": "dem.tif"}, "render": render,
                                   "study": study}))  # fmt: skip
    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(app, ["run", str(exp), "--out", "out", "--no-progress"])
    assert r.exit_code == 0, r.output
    assert "are NaN (holes)" in r.output  # the note that says what is filled
    rows = list(csv.DictReader((tmp_path / "out" / "results.csv").read_text().splitlines()))
    assert rows and all(math.isfinite(float(x["value"])) for x in rows)
    figures = {p.name for p in (tmp_path / "out" / "figures").glob("*.png")}
    assert figures
    if kind == "sampling":
        # the planner panels (of the wavelet plan), the reconstructions' panels, the sparse mesh
        assert {"sparse_mesh_unit0.png", "panels_unit0.png", "recon_panels_unit0.png"} <= figures


def test_the_sparse_mesh_keeps_the_holes_and_reads_no_nan(tmp_path):
    # the figure's rebuilt terrain: samples planned in a hole read the nearest cell with a
    # height (before: "values contains NaN" from the Delaunay reconstruction, even with
    # --no-figures), and the rebuilt terrain has the holes of the one it rebuilds
    from simlunar.pipeline import figure_inputs as fi

    h = ndimage.gaussian_filter(np.random.default_rng(1).standard_normal((30, 40)), 2)
    h[:6, :6] = np.nan
    terrain = Terrain(h, np.full(h.shape, 0.2, np.float32), 0.2, (0.0, 0.0))
    seen = {}

    class Scene:
        bsdf = None

        def __init__(self):
            self.terrain = terrain

        def render(self, t, *, bsdf):
            seen["heights"] = t.heights
            return type("R", (), {"image": np.ones((*t.heights.shape, 3), np.float32)})()

    image = np.where(np.isnan(h), 0.0, 0.5 + 0.1 * np.nan_to_num(h))
    energy = np.zeros(h.shape)
    energy[:6, :6] = 1.0  # every sample planned inside the hole
    energy += 1e-9
    fi.sparse_mesh_render(Scene(), image, density=1 / 64, rng=0, energy=energy)
    rebuilt = seen["heights"]
    assert np.array_equal(np.isnan(rebuilt), np.isnan(h))
    assert np.isfinite(rebuilt[~np.isnan(h)]).all()
