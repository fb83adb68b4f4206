"""The preflight checks' own mathematics and file handling (hand-computed cases)."""

from __future__ import annotations

import hashlib
import warnings

import numpy as np
import pytest

from simlunar.errors import ConfigError
from simlunar.pipeline.inputs import TerrainFacts, input_files, input_hashes
from simlunar.pipeline.preflight import _ray_box, check_study_sizes
from simlunar.results.store import file_sha256

LO, HI = np.array([0.0, -10.0, -1.0]), np.array([20.0, 0.0, 1.0])


@pytest.mark.parametrize(
    ("origin", "direction", "hits"),
    [
        ((10, -5, 30), (0, 0, -1), True),  # straight down into the box
        ((10, -5, 30), (0, 0, 1), False),  # straight up, away from it
        ((10, -5, 0), (0, 0, 1), True),  # starts inside the box
        ((-10, -5, 0), (1, 0, 0), True),  # parallel to z and y slabs, inside them, towards it
        ((-10, -5, 5), (1, 0, 0), False),  # parallel to the z slab but above it
        ((30, -5, 30), (0, 0, -1), False),  # beside the footprint
        ((-10, -5, 10), (1, 0, -0.5), True),  # oblique: reaches z = 1 at x = 8
        ((-10, -5, 10), (1, 0, -0.1), False),  # oblique: still at z = 7 at x = 20
    ],
)
def test_ray_box_by_hand(origin, direction, hits):
    o = np.array([origin], float)
    d = np.array([direction], float)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    assert bool(_ray_box(o, d, LO, HI)[0]) is hits


def test_terrain_facts_extent_follows_the_terrain_convention():
    f = TerrainFacts(rows=10, cols=20, spacing=0.5, origin=(1.0, 2.0), zmin=0, zmax=1)
    # columns run to +x, rows to -y from the top-left corner
    assert f.extent == (1.0, 11.0, -3.0, 2.0)


def test_density_sample_counts_are_checked_on_the_units_image():
    from types import SimpleNamespace

    study = SimpleNamespace(kind="sampling", densities=[0.5, 3 / 1000])
    cfg = SimpleNamespace(study=study)
    check_study_sizes(cfg, (40, 25))  # 1000 pixels: 3 samples, just enough
    study.densities = [0.5, 2.4 / 1000]  # rounds to 2
    with pytest.raises(ConfigError, match=r"study.densities\[1\]: density 0.0024 gives 2 samples"):
        check_study_sizes(cfg, (40, 25))


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
