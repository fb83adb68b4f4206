"""Reconstruction export: GeoTIFF and EXR written, read back with rasterio and OpenEXR.

The round trips check values, the georeference (transform, CRS) and the error map's sign; a
shrunken quickstart through ``simlunar run --save-arrays`` checks the runner writes one folder
per unit, recomputes a unit only for a missing export, and leaves results.csv and the unit
cache keys as they are without the flag.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import OpenEXR
import pytest
import rasterio
from rasterio.crs import CRS
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.errors import ConfigError
from simlunar.geometry import Camera, Intrinsics, OrthoCamera, Pose
from simlunar.imaging.exr import read_exr
from simlunar.results import array_exports as ax
from simlunar.terrain.types import Terrain

ROOT = Path(__file__).resolve().parents[2]
QUICKSTART = str(ROOT / "experiments" / "quickstart.yaml")
#: the projected Moon CRS simlunar writes for DEMs (IAU 2015 authority of PROJ)
MOON = CRS.from_string("IAU_2015:30110").to_wkt()


def _terrain(crs=None):
    rng = np.random.default_rng(0)
    h = rng.normal(size=(6, 8))
    return Terrain(h, np.full((6, 8), 0.2, np.float32), 0.5, (100.0, 200.0), crs=crs)


def _payload(crs=MOON):
    t = _terrain(crs)
    cam = OrthoCamera.nadir_for_grid(t.shape, t.spacing, t.origin, altitude=50.0)
    view = ax.export_view(cam, t)
    depth = 50.0 - t.heights  # what a nadir camera at z = 50 m measures
    recon = depth + np.linspace(-0.3, 0.3, depth.size).reshape(depth.shape)
    grids = {("wavelet_lloyd", 0, "linear"): recon, ("random", 1, "shading"): depth + 0.25}
    payload = ax.array_export_payload(
        grids, depth, densities=[1 / 4, 1 / 16], ks=[12, 3], view=view
    )
    return t, depth, recon, payload


def test_density_tags():
    assert ax.density_tag(1 / 64) == "1-64"
    assert ax.density_tag(0.5) == "1-2"
    assert ax.density_tag(1.0) == "1-1"
    assert ax.density_tag(0.3) == "0.3"
    assert ax.density_tag(1 / 6.9) == "0.1449"
    assert ax.density_tag(0.0) == "all"
    with pytest.raises(ValueError, match="density"):
        ax.density_tag(1.5)


def test_a_nadir_view_exports_heights_on_the_terrain_grid():
    t = _terrain(MOON)
    cam = OrthoCamera.nadir_for_grid(t.shape, t.spacing, t.origin, altitude=50.0)
    view = ax.export_view(cam, t)
    assert view["quantity"] == "height" and view["offset"] == 50.0
    # CONTRIBUTING.md: north-up transform (s, 0, x0, 0, -s, y0)
    assert view["transform"] == (0.5, 0.0, 100.0, 0.0, -0.5, 200.0)
    assert view["crs"] == MOON
    # height = camera z - depth: a hand-computed cell
    _, _depth, recon, payload = _payload()
    item = payload["items"][0]
    assert item["grid"][2, 3] == pytest.approx(50.0 - recon[2, 3], abs=1e-5)
    np.testing.assert_allclose(payload["truth"], t.heights, atol=1e-5)


def test_a_perspective_view_exports_depth_on_the_pixel_grid():
    t = _terrain()
    cam = Camera(Intrinsics.from_fov(8, 6, 40.0), Pose.look_at((0, 0, 10), (0, 0, 0), (0, 1, 0)))
    view = ax.export_view(cam, t)
    assert view == {
        "quantity": "depth",
        "offset": None,
        "transform": (1.0, 0.0, 0.0, 0.0, -1.0, 6.0),  # 6 rows: bottom-left corner at 0
        "crs": None,
    }
    # an orthographic camera that is not over the terrain grid is no terrain grid either
    tilted = OrthoCamera.nadir_for_grid((3, 4), 0.5, t.origin)
    assert ax.export_view(tilted, t)["quantity"] == "depth"


def test_write_then_read_back_with_rasterio_and_openexr(tmp_path):
    _t, _depth, recon, payload = _payload()
    folder = ax.write_array_export(tmp_path / "unit0", payload, unit_key="abc")
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["unit_key"] == "abc" and manifest["quantity"] == "height"
    names = {f["tif"] for f in manifest["files"]}
    assert names == {
        "truth_height.tif",
        "wavelet_lloyd_1-4_linear_height.tif",
        "wavelet_lloyd_1-4_linear_error.tif",
        "random_1-16_shading_height.tif",
        "random_1-16_shading_error.tif",
    }
    entry = next(f for f in manifest["files"] if f["tif"] == "random_1-16_shading_error.tif")
    assert (entry["planner"], entry["density"], entry["k"]) == ("random", 1 / 16, 3)
    assert (entry["reconstruction"], entry["trial"]) == ("shading", 0)

    height = (50.0 - recon).astype(np.float32)
    with rasterio.open(folder / "wavelet_lloyd_1-4_linear_height.tif") as src:
        assert src.count == 1 and src.dtypes[0] == "float32"
        assert src.descriptions[0] == "height"
        assert tuple(src.transform)[:6] == (0.5, 0.0, 100.0, 0.0, -0.5, 200.0)
        assert src.crs == CRS.from_wkt(MOON)
        np.testing.assert_array_equal(src.read(1), height)
        assert src.tags()["planner"] == "wavelet_lloyd"
    # error = reconstruction - truth, in heights: a depth too large is a surface too low
    grid, transform, crs, name = ax.read_geotiff(folder / "random_1-16_shading_error.tif")
    assert name == "error" and crs is not None
    np.testing.assert_allclose(grid, -0.25, atol=1e-5)
    assert transform == (0.5, 0.0, 100.0, 0.0, -0.5, 200.0)

    # the EXR, read with OpenEXR itself: one float32 channel named after the quantity
    with OpenEXR.File(str(folder / "wavelet_lloyd_1-4_linear_height.exr")) as f:
        channels = f.channels()
        assert list(channels) == ["height"]
        pixels = channels["height"].pixels
        assert pixels.dtype == np.float32
        np.testing.assert_array_equal(pixels, height)
    exr = read_exr(folder / "wavelet_lloyd_1-4_linear_error.exr")
    np.testing.assert_array_equal(
        exr["error"], (height.astype(np.float64) - payload["truth"]).astype(np.float32)
    )
    assert ax.array_export_complete(folder, "abc")
    assert not ax.array_export_complete(folder, "other")
    (folder / "random_1-16_shading_error.exr").unlink()
    assert not ax.array_export_complete(folder, "abc")


def test_without_a_crs_no_crs_is_written(tmp_path):
    _, _, _, payload = _payload(crs=None)
    folder = ax.write_array_export(tmp_path / "u", payload)
    _grid, transform, crs, _ = ax.read_geotiff(folder / "truth_height.tif")
    assert crs is None and transform == (0.5, 0.0, 100.0, 0.0, -0.5, 200.0)
    assert "unit_key" not in json.loads((folder / "manifest.json").read_text())


def test_nan_cells_stay_nan(tmp_path):
    a = np.array([[1.0, np.nan], [3.0, 4.0]])
    path = ax.write_geotiff(tmp_path / "a.tif", a, name="depth")
    grid, transform, crs, name = ax.read_geotiff(path)
    assert np.isnan(grid[0, 1]) and grid[1, 1] == 4.0
    assert (transform, crs, name) == ((1.0, 0.0, 0.0, 0.0, -1.0, 2.0), None, "depth")
    with pytest.raises(ValueError, match="2-D"):
        ax.write_geotiff(tmp_path / "b.tif", np.zeros(3))


def test_check_save_arrays_refuses_a_scanner_study():
    class Cfg:
        name = "s"

        class study:
            kind = "scanner"

    with pytest.raises(ConfigError, match=r"--save-arrays.*sampling and lidar"):
        ax.check_save_arrays(Cfg)


SMALL = [
    *("--set", "terrain.scale=0.0625"),
    *("--set", "render.spp=2"),
    *("--set", "study.strategies=[random, wavelet_lloyd]"),
    *("--set", "study.strategy_options={wavelet_lloyd: {strategy: wavelet, placement: lloyd}}"),
    *("--set", "study.densities=[1/16, 1/64]"),
    *("--set", "study.trials=2"),
    *("--set", "study.metrics=[mse]"),
    *("--set", "study.reconstructions=[linear]"),
]


@pytest.mark.render
@pytest.mark.slow
def test_run_with_save_arrays_writes_the_reconstructions(tmp_path):
    def run(out, *extra):
        args = ["run", QUICKSTART, "--out", str(out), "--no-progress", "--no-figures", *SMALL]
        r = CliRunner().invoke(app, [*args, *extra])
        assert r.exit_code == 0, r.output
        return r

    plain, saved = tmp_path / "plain", tmp_path / "saved"
    run(plain)
    assert not (plain / "arrays").exists()
    run(saved, "--save-arrays")
    folder = saved / "arrays" / "unit0"
    names = {p.name for p in folder.iterdir()}
    for stem in ("random_1-16_linear", "wavelet_lloyd_1-64_linear"):
        assert {f"{stem}_{q}.{e}" for q in ("height", "error") for e in ("tif", "exr")} <= names
    assert "truth_height.tif" in names
    # results and cache keys do not depend on the flag
    assert (plain / "results.csv").read_bytes() == (saved / "results.csv").read_bytes()
    assert sorted(p.name for p in (plain / "units").iterdir()) == sorted(
        p.name for p in (saved / "units").iterdir()
    )
    # the export is the truth plus the error, on the aerial grid (0.2 m cells at any scale)
    h, transform, _, _ = ax.read_geotiff(folder / "random_1-16_linear_height.tif")
    e, _, _, _ = ax.read_geotiff(folder / "random_1-16_linear_error.tif")
    t, _, _, _ = ax.read_geotiff(folder / "truth_height.tif")
    np.testing.assert_allclose(h - t, e, atol=1e-4)
    assert transform[0] == -transform[4] == pytest.approx(0.2)
    assert np.abs(e).max() > 0  # 1/16 of the cells measured: the rest is interpolated

    # a missing export is written again on the next run, results unchanged
    (folder / "manifest.json").unlink()
    r = run(saved, "--save-arrays")
    assert "1 computed" in r.output and (folder / "manifest.json").is_file()
    assert (plain / "results.csv").read_bytes() == (saved / "results.csv").read_bytes()
    # without the flag, the folder's exports go (the folder says save_arrays: false)
    run(saved)
    assert not (saved / "arrays").exists()
