"""A unit's input files (simlunar/pipeline/inputs.py): which files it reads and their SHA-256,
the files' checks during a run, and the terrain facts read from a DEM before anything is built
(hand-made files; every error path with its one-line message)."""

from __future__ import annotations

import hashlib
import json
import warnings

import numpy as np
import pytest

from simlunar.errors import ConfigError
from simlunar.pipeline.inputs import (
    MIN_SPACING_M,
    TerrainFacts,
    check_dem_file,
    gdal_files,
    input_files,
    input_hashes,
    model_files,
    terrain_facts,
)
from simlunar.results.store import file_sha256


def _npy(path, heights, spacing=0.5):
    """A ``.npy`` DEM with its ``.json`` side file (the spacing)."""
    np.save(path, np.asarray(heights, np.float64))
    path.with_name(path.name + ".json").write_text(json.dumps({"spacing": spacing}))
    return path


def _write(path, data: bytes):
    path.write_bytes(data)
    return path


# --- which files, their hashes and their checks during a run --------------------------------


def test_model_files_by_hand():
    # every planner option that names a learned model, with its .json record, by key path;
    # options without a model and sections that are not dicts are ignored
    study = {
        "strategy_options": {"l": {"feature_opts": {"model": "m/a.joblib"}}, "w": {}, "n": None},
        "planner_opts": {"p": {"feature_opts": {"model": "b.joblib"}}, "q": "text"},
        "options": {"planner_opts": {"r": {"feature_opts": {"model": "c.joblib"}}}},
    }
    got = model_files(study)
    assert {k: str(v) for k, v in got.items()} == {
        "study.strategy_options.l.feature_opts.model": "m/a.joblib",
        "study.strategy_options.l.feature_opts.model.json": "m/a.json",
        "study.planner_opts.p.feature_opts.model": "b.joblib",
        "study.planner_opts.p.feature_opts.model.json": "b.json",
        "study.options.planner_opts.r.feature_opts.model": "c.joblib",
        "study.options.planner_opts.r.feature_opts.model.json": "c.json",
    }
    assert model_files({}) == {} and model_files({"options": "x", "planner_opts": [1]}) == {}


def test_input_files_albedo_missing_preset_and_npy_without_side_file(tmp_path):
    dem = tmp_path / "dem.npy"
    np.save(dem, np.zeros((3, 4)))  # no dem.npy.json
    alb = tmp_path / "alb.npy"
    cfg = {"terrain": {"file": str(dem), "albedo_file": str(alb), "preset": "no_such_preset"}}
    # a missing preset is left to the checks (no key); the albedo is named even before it exists
    assert input_files(cfg) == {"terrain.file": dem, "terrain.albedo_file": alb}
    assert input_files({}) == {}


def test_gdal_files_is_empty_for_own_formats_missing_and_unreadable_files(tmp_path):
    dem = _npy(tmp_path / "dem.npy", np.zeros((3, 3)))
    assert gdal_files(dem) == []
    assert gdal_files(tmp_path / "missing.tif") == []
    junk = tmp_path / "junk.tif"
    junk.write_bytes(b"not a raster at all")
    assert gdal_files(junk) == []  # reported by the checks, not here


def test_input_hashes_name_an_unreadable_file_and_hint_at_training(tmp_path):
    missing = tmp_path / "gone.npy"
    with pytest.raises(ConfigError, match=rf"^terrain.file: cannot read {missing} \(No such file"):
        input_hashes({"terrain": {"file": str(missing)}})
    opts = {"l": {"feature_opts": {"model": str(tmp_path / "m.joblib")}}}
    with pytest.raises(ConfigError, match=r"a learned model: make it with `simlunar train"):
        input_hashes({"study": {"strategy_options": opts}})


# --- terrain facts ------------------------------------------------------------------------------


def test_check_dem_file_facts_by_hand(tmp_path):
    big = np.arange(400.0).reshape(20, 20)
    big[0, 0] = np.nan  # 1 of 400 = 0.25 % holes
    f = check_dem_file(_npy(tmp_path / "dem.npy", big, spacing=0.25), key="dem")
    assert (f.rows, f.cols, f.spacing) == (20, 20, 0.25)
    assert (f.zmin, f.zmax) == (1.0, 399.0)
    assert f.nan_fraction == pytest.approx(1 / 400)
    assert f.zmid == float(np.median(big[np.isfinite(big)]))  # 200.0
    assert f.zmid == 200.0 and f.source == str(tmp_path / "dem.npy")


@pytest.mark.parametrize(
    ("make", "msg"),
    [
        (lambda d: d / "missing.npy", "dem: file not found: "),
        (lambda d: _write(d / "e.npy", b""), "is empty"),
        (lambda d: _write(d / "t.npy", b"heights"), "is not a NumPy .npy file"),
        (lambda d: _npy(d / "row.npy", np.zeros((1, 5))), "at least 2 x 2 cells, got 1 x 5"),
        (lambda d: _npy(d / "nan.npy", np.full((3, 3), np.nan)), "every height is NaN"),
        (
            lambda d: _npy(d / "holes.npy", np.where(np.eye(4) > 0, np.nan, 0.0)),
            r"25.0% of the heights are NaN \(holes\); at most 5% are filled",
        ),
        (lambda d: _npy(d / "high.npy", np.full((3, 3), 2e6)), "heights reach 2e\\+06 m"),
        (lambda d: _npy(d / "tiny.npy", np.zeros((3, 3)), spacing=1e-9), "below 1e-06 m"),
        (
            lambda d: _npy(d / "wide.npy", np.zeros((3, 3)), spacing=5e5),
            r"the terrain reaches 1.5e\+06 m from the origin",
        ),
    ],
)
def test_check_dem_file_errors(tmp_path, make, msg):
    with pytest.raises(ConfigError, match=msg) as err:
        check_dem_file(make(tmp_path), key="dem")
    assert str(err.value).startswith("dem: ") and "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("spacing", "msg"),
    [
        (
            np.array([0.5, 0.5]),
            r"'spacing' must be one number \(metres per cell\), got shape \[2\]",
        ),
        (np.array(-1.0), "'spacing' must be a positive number, got -1.0"),
        (np.array("x"), "'spacing' must be one number"),
    ],
)
def test_check_dem_file_npz_spacing_errors(tmp_path, spacing, msg):
    p = tmp_path / "dem.npz"
    np.savez(p, heights=np.zeros((3, 3)), spacing=spacing)
    with pytest.raises(ConfigError, match=msg):
        check_dem_file(p, key="dem")


def test_min_spacing_is_a_micrometre():
    assert MIN_SPACING_M == 1e-6


def test_terrain_facts_of_a_file_and_of_a_preset(tmp_path):
    from types import SimpleNamespace

    dem = _npy(tmp_path / "dem.npy", np.arange(9.0).reshape(3, 3))
    t = SimpleNamespace(preset=None, file=str(dem), albedo_file=None, spacing_m=None)
    f = terrain_facts(t)
    assert (f.rows, f.cols, f.zmin, f.zmax) == (3, 3, 0.0, 8.0)
    # the memo follows the file: rewritten (another size / mtime), it is read again
    _npy(dem, np.arange(16.0).reshape(4, 4))
    assert terrain_facts(t).rows == 4
    missing = SimpleNamespace(
        preset=None, file=str(tmp_path / "no.npy"), albedo_file=None, spacing_m=None
    )
    with pytest.raises(ConfigError, match=r"terrain\.file: file not found"):
        terrain_facts(missing)
    bad = SimpleNamespace(preset="no_such_preset", scale=1.0, overrides=None)
    with pytest.raises(ConfigError, match=r"^terrain\.preset: "):
        terrain_facts(bad)


# --- moved from test_preflight.py ----------------------------------------------------------


def test_terrain_facts_extent_follows_the_terrain_convention():
    f = TerrainFacts(rows=10, cols=20, spacing=0.5, origin=(1.0, 2.0), zmin=0, zmax=1)
    # columns run to +x, rows to -y from the top-left corner
    assert f.extent == (1.0, 11.0, -3.0, 2.0)


def test_input_hashes_are_the_sha256_of_the_files_and_follow_their_contents(tmp_path):
    dem = tmp_path / "dem.npy"
    np.save(dem, np.zeros((3, 4)))
    (tmp_path / "dem.npy.json").write_text('{"spacing": 0.2}')
    cfg = {"terrain": {"file": str(dem), "albedo_file": None}}
    assert set(input_files(cfg)) == {"terrain.file", "terrain.file.json"}
    h1 = input_hashes(cfg)["terrain.file"]["sha256"]
    assert h1 == hashlib.sha256(dem.read_bytes()).hexdigest() == file_sha256(dem)
    np.save(dem, np.ones((3, 4)))
    assert input_hashes(cfg)["terrain.file"]["sha256"] != h1
    preset = input_files({"terrain": {"preset": "aerial_1"}})["terrain.preset"]
    assert preset.name == "aerial_1.yaml" and preset.is_file()


def _tif(path, heights, *, georef=True):
    import rasterio
    from rasterio.transform import Affine

    kw = {"transform": Affine(0.5, 0, 0, 0, -0.5, 0)} if georef else {}
    rows, cols = heights.shape
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rasterio.errors.NotGeoreferencedWarning)
        with rasterio.open(
            path, "w", driver="GTiff", width=cols, height=rows, count=1, dtype="float32", **kw
        ) as dst:
            dst.write(heights.astype(np.float32), 1)


_VRT = """<VRTDataset rasterXSize="5" rasterYSize="4">
  <GeoTransform>0, 0.5, 0, 0, 0, -0.5</GeoTransform>
  <VRTRasterBand dataType="Float32" band="1">
    <SimpleSource>
      <SourceFilename relativeToVRT="1">src.tif</SourceFilename>
      <SourceBand>1</SourceBand>
    </SimpleSource>
  </VRTRasterBand>
</VRTDataset>
"""


def test_the_cache_key_follows_the_tif_a_vrt_points_to(tmp_path):
    from simlunar.pipeline.runner import unit_key

    _tif(tmp_path / "src.tif", np.zeros((4, 5)))
    (tmp_path / "dem.vrt").write_text(_VRT)
    cfg = {"terrain": {"file": str(tmp_path / "dem.vrt")}}
    files = input_files(cfg)
    assert files["terrain.file+src.tif"] == tmp_path / "src.tif"
    k1 = unit_key(cfg)
    _tif(tmp_path / "src.tif", np.ones((4, 5)))  # the .vrt itself is unchanged
    assert unit_key(cfg) != k1


def test_the_cache_key_follows_a_world_file(tmp_path):
    from simlunar.pipeline.runner import unit_key

    _tif(tmp_path / "dem.tif", np.zeros((4, 5)), georef=False)
    (tmp_path / "dem.tfw").write_text("0.5\n0\n0\n-0.5\n0.25\n-0.25\n")
    cfg = {"terrain": {"file": str(tmp_path / "dem.tif")}}
    assert "terrain.file+dem.tfw" in input_files(cfg)
    k1 = unit_key(cfg)
    (tmp_path / "dem.tfw").write_text("0.2\n0\n0\n-0.2\n0.1\n-0.1\n")  # another spacing
    assert unit_key(cfg) != k1
    # a plain GeoTIFF reads one file
    _tif(tmp_path / "plain.tif", np.zeros((4, 5)))
    assert set(input_files({"terrain": {"file": str(tmp_path / "plain.tif")}})) == {"terrain.file"}


def test_a_learned_model_and_its_record_are_inputs_of_the_unit(tmp_path):
    # a model retrained at the same path must not reuse the units of the old one
    from simlunar.pipeline.runner import unit_key

    model = tmp_path / "m.joblib"
    model.write_bytes(b"model one")
    model.with_suffix(".json").write_text("{}")
    opts = {"l": {"strategy": "learned", "feature_opts": {"model": str(model)}}, "w": {}}
    config = {"name": "x", "study": {"strategy_options": opts}}
    inputs = input_hashes(config)
    key = "study.strategy_options.l.feature_opts.model"
    assert set(inputs) == {key, f"{key}.json"}
    assert inputs[key]["path"] == str(model)
    before = unit_key(config, inputs)
    model.write_bytes(b"model two")
    assert unit_key(config, input_hashes(config)) != before


def test_scanner_frame_budget_asks_each_scanned_coding_for_its_frames(monkeypatch):
    # 256 x 192 projector and camera: 98 304 pixels per frame. The gray code captures
    # 2 (8 + 8) + 2 = 34 frames; an 8-step phase shift 2 axes x 3 levels x 8 + 2 = 50
    # (coding.frames). A limit of 40 frames' pixels passes the one and stops the other.
    from simlunar.config.scanner import ScannerStudyCfg
    from simlunar.pipeline.preflight import check_scanner_budget

    monkeypatch.setenv("SIMLUNAR_MAX_FRAME_PIXELS", str(40 * 98_304))
    base = {"kind": "scanner", "projector_px": [256, 192], "camera_px": [256, 192]}
    phase = {"phase_opts": {"steps": 8}}
    check_scanner_budget(ScannerStudyCfg(**base, modes=["gray_code"]))
    check_scanner_budget(ScannerStudyCfg(**base, modes=["data_reduction"], options=phase))
    with pytest.raises(ConfigError, match=r"study\.projector_px: 50 phase-shift frames x 98304"):
        check_scanner_budget(ScannerStudyCfg(**base, modes=["phase_shift"], options=phase))
    # ambiguity enhancement scans with study.coding
    with pytest.raises(ConfigError, match="50 phase-shift frames"):
        check_scanner_budget(
            ScannerStudyCfg(
                **base, modes=["ambiguity_enhancement"], coding="phase_shift", options=phase
            )
        )
