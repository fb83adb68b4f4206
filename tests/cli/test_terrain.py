"""`simlunar terrain`: files written, seeds, one-line errors with exit code 2."""

import json

import numpy as np
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.config.translate import preset_params
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
    ref = generate(preset_params("aerial_3"), rng=5, scale=0.05)
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


def test_terrain_stats_prints_slopes_hurst_and_densities(tmp_path):
    r = runner.invoke(app, ["terrain", "aerial_3", "--stats", "--scale", "0.05", "--seed", "5"])
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    slope_rows = [ln for ln in lines if ln.count("°") == 2]
    assert len(slope_rows) >= 3
    assert any(ln.startswith("Hurst exponent H = ") for ln in lines)
    assert any(ln.startswith("rocks per 100 m^2") for ln in lines)
    # the numbers are those of the library on the same terrain
    from simlunar.terrain.stats import roughness

    ref = generate(preset_params("aerial_3"), rng=5, scale=0.05).terrain
    h = roughness(ref.heights, ref.spacing).hurst
    assert f"H = {h:.3f}" in r.output
    # and a DEM file (a GeoTIFF written by the command) gives the same roughness
    out = tmp_path / "t"
    r = runner.invoke(
        app, ["terrain", "aerial_3", "--scale", "0.05", "--seed", "5", "--out", str(out),
              "--format", "tif", "--mesh", "none"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["terrain", str(out / "dem.tif"), "--stats"])
    assert r.exit_code == 0, r.output
    assert f"H = {h:.3f}" in r.output  # float32 on disk: same to 3 decimals
    # the densities come from the features.json beside the DEM, as for the generated terrain
    dens = [ln for ln in lines if ln.startswith(("craters", "rocks"))]
    assert dens and all(d in r.output for d in dens)
    (out / "features.json").unlink()
    r = runner.invoke(app, ["terrain", str(out / "dem.tif"), "--stats"])
    assert r.exit_code == 0 and "unknown" in r.output
    r = runner.invoke(app, ["terrain", "aerial_3"])
    assert r.exit_code == 2 and "--out" in r.output


def test_terrain_reads_a_preset_as_experiments_do(tmp_path):
    """Unit strings (``spacing_m: "20 cm"``) go through the schema's models, as in an
    experiment's terrain; the old preset reader refused them."""
    import yaml

    from simlunar.config.terrain import SCENES

    data = yaml.safe_load((SCENES / "aerial_3.yaml").read_text())
    data["grid"]["spacing_m"] = "20 cm"
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump(data))
    r = runner.invoke(app, ["terrain", str(path), "--stats", "--scale", "0.05", "--seed", "5"])
    assert r.exit_code == 0, r.output
    assert r.output.splitlines()[0].startswith("aerial_3: 50 x 80 cells at 0.2 m")
    ref = runner.invoke(app, ["terrain", "aerial_3", "--stats", "--scale", "0.05", "--seed", "5"])
    assert r.output.splitlines()[1:] == ref.output.splitlines()[1:]  # the same terrain
    r = runner.invoke(app, ["terrain", "aerial_3", "--stats", "--scale", "1.5"])
    assert r.exit_code == 2 and "--scale" in r.output


def test_terrain_stats_with_a_malformed_features_json_is_one_line(tmp_path):
    out = tmp_path / "t"
    r = runner.invoke(
        app, ["terrain", "aerial_3", "--scale", "0.05", "--out", str(out), "--format", "npz",
              "--mesh", "none"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    side = out / "features.json"
    for bad in ('["not", "a", "mapping"]', '{"craters": [{"x": 1}]}', '{"rocks": 3}', "{"):
        side.write_text(bad)
        r = runner.invoke(app, ["terrain", str(out / "dem.npz"), "--stats"])
        assert r.exit_code == 2, (bad, r.output)
        assert "Traceback" not in r.output
        err = [ln for ln in r.output.splitlines() if ln.startswith("error: ")]
        assert len(err) == 1 and str(side) in err[0], r.output
