"""`simlunar terrain`: files written, seeds, one-line errors with exit code 2."""

import json

import numpy as np
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.terrain import generate
from simlunar.terrain.io import load_dem

runner = CliRunner()


def test_terrain_command_writes_everything(tmp_path):
    out = tmp_path / "t"
    r = runner.invoke(
        app,
        [
            "terrain",
            "aerial_3",
            "--out",
            str(out),
            "--seed",
            "5",
            "--scale",
            "0.05",
            "--format",
            "npz",
        ],
    )
    assert r.exit_code == 0, r.output
    names = sorted(p.name for p in out.iterdir())
    assert names == ["albedo.png", "dem.npz", "features.json", "hillshade.png", "mesh.ply"]
    t = load_dem(out / "dem.npz")
    ref = generate("aerial_3", rng=5, scale=0.05)
    np.testing.assert_array_equal(t.heights, ref.terrain.heights.astype(np.float32))
    feats = json.loads((out / "features.json").read_text())
    assert feats["name"] == "aerial_3" and feats["spacing"] == 0.2
    assert len(feats["craters"]) == len(ref.craters) and len(feats["rocks"]) == len(ref.rocks)
    assert set(feats["rocks"][0]) >= {"x", "y", "diameter", "height"}
    assert set(feats["craters"][0]) >= {"x", "y", "diameter", "depth", "rim_height", "age_myr"}


def test_terrain_command_errors_are_one_line(tmp_path):
    r = runner.invoke(app, ["terrain", "nope", "--out", str(tmp_path / "x")])
    assert r.exit_code == 2 and "unknown terrain preset 'nope'" in r.output
    bad = tmp_path / "bad.yaml"
    bad.write_text("grid: {rows: 32, cols: 32, spacing_m: -1}\n")
    r = runner.invoke(app, ["terrain", str(bad), "--out", str(tmp_path / "y")])
    assert r.exit_code == 2 and "grid.spacing_m" in r.output and "Traceback" not in r.output
    r = runner.invoke(app, ["terrain", "moonyard", "--out", str(tmp_path / "z"), "--mesh", "stl"])
    assert r.exit_code == 2 and "--mesh" in r.output
