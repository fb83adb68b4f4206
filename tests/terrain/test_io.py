"""DEM round trips, foreign DEMs, bad files, mesh export, hillshade."""

import json

import numpy as np
import pytest
import trimesh
from PIL import Image

from simlunar.terrain import Terrain
from simlunar.terrain import io as tio


@pytest.fixture
def terrain(rng):
    h = rng.normal(size=(23, 37)).astype(np.float32).astype(np.float64)
    h[3, 4] = np.nan
    h[10, 0] = np.nan
    a = rng.random((23, 37)).astype(np.float32)
    return Terrain(h, a, spacing=0.123456789, origin=(12.5, -7.25))


@pytest.mark.parametrize("ext", [".npy", ".npz", ".exr", ".tif", ".tiff"])
def test_round_trip_bit_identical_with_spacing_origin_and_nodata(tmp_path, terrain, ext):
    p = tio.save_dem(tmp_path / f"dem{ext}", terrain)
    back = tio.load_dem(p)
    assert back.heights.astype(np.float32).tobytes() == terrain.heights.astype(np.float32).tobytes()
    assert back.albedo.tobytes() == terrain.albedo.tobytes()
    np.testing.assert_array_equal(back.nodata, terrain.nodata)
    assert back.nodata.sum() == 2
    assert back.spacing == terrain.spacing and back.origin == terrain.origin
    # and again: a loaded terrain saves to the same bytes
    p2 = tio.save_dem(tmp_path / f"dem2{ext}", back)
    again = tio.load_dem(p2)
    assert again.heights.tobytes() == back.heights.tobytes()


def test_foreign_single_band_dems(tmp_path):
    import tifffile

    z = np.arange(20, dtype=np.int16).reshape(4, 5)
    z[0, 0] = -9999
    tifffile.imwrite(tmp_path / "foreign.tif", z)
    with pytest.raises(ValueError, match=r"foreign\.tif.*spacing"):
        tio.load_dem(tmp_path / "foreign.tif")
    t = tio.load_dem(tmp_path / "foreign.tif", spacing=2.0, nodata=-9999)
    assert t.spacing == 2.0 and t.origin == (0.0, 0.0)
    assert np.isnan(t.heights[0, 0]) and t.heights[3, 4] == 19
    assert np.all(t.albedo == np.float32(tio.DEFAULT_ALBEDO))
    np.save(tmp_path / "plain.npy", np.ones((4, 5)))
    assert tio.load_dem(tmp_path / "plain.npy", spacing=0.5, origin=(1, 2)).origin == (1.0, 2.0)


def test_bad_dem_files_name_the_file(tmp_path):
    np.save(tmp_path / "cube.npy", np.zeros((3, 4, 5)))
    with pytest.raises(ValueError, match=r"cube\.npy.*shape"):
        tio.load_dem(tmp_path / "cube.npy", spacing=1.0)
    np.save(tmp_path / "words.npy", np.array([["a", "b"], ["c", "d"]]))
    with pytest.raises(ValueError, match=r"words\.npy.*dtype"):
        tio.load_dem(tmp_path / "words.npy", spacing=1.0)
    np.save(tmp_path / "cplx.npy", np.zeros((3, 3), complex))
    with pytest.raises(ValueError, match=r"cplx\.npy.*dtype"):
        tio.load_dem(tmp_path / "cplx.npy", spacing=1.0)
    (tmp_path / "junk.exr").write_bytes(b"junk" * 50)
    with pytest.raises(ValueError, match=r"junk\.exr"):
        tio.load_dem(tmp_path / "junk.exr")
    (tmp_path / "junk.npz").write_bytes(b"junk" * 50)
    with pytest.raises(ValueError, match=r"junk\.npz"):
        tio.load_dem(tmp_path / "junk.npz")
    np.savez(tmp_path / "noh.npz", z=np.zeros((3, 3)))
    with pytest.raises(ValueError, match=r"noh\.npz.*heights"):
        tio.load_dem(tmp_path / "noh.npz")
    with pytest.raises(FileNotFoundError, match=r"nothere\.npz"):
        tio.load_dem(tmp_path / "nothere.npz")
    with pytest.raises(ValueError, match=r"\.png"):
        tio.load_dem(tmp_path / "x.png")
    with pytest.raises(ValueError, match=r"bad\.npy.*spacing"):
        np.save(tmp_path / "bad.npy", np.zeros((3, 3)))
        tio.load_dem(tmp_path / "bad.npy", spacing=-1.0)


def test_npy_sidecar_holds_spacing(tmp_path, terrain):
    tio.save_dem(tmp_path / "d.npy", terrain)
    meta = json.loads((tmp_path / "d.npy.json").read_text())
    assert meta["spacing"] == terrain.spacing and meta["origin"] == list(terrain.origin)
    assert np.load(tmp_path / "d.npy").shape == (2, 23, 37)


@pytest.mark.parametrize("ext", [".ply", ".obj"])
def test_mesh_export_one_vertex_per_cell_and_extent(tmp_path, ext):
    h = np.add.outer(np.arange(6.0), np.arange(9.0)) * 0.1
    a = np.full((6, 9), 0.5, np.float32)
    t = Terrain(h, a, spacing=0.5, origin=(10.0, 20.0))
    p = tio.export_mesh(t, tmp_path / f"m{ext}")
    m = trimesh.load(p, process=False)
    assert len(m.vertices) == 6 * 9
    assert len(m.faces) == 2 * 5 * 8
    # vertices at cell centres: x in [10.25, 14.25], y in [17.25, 19.75]
    np.testing.assert_allclose(m.vertices[:, 0].min(), 10.25)
    np.testing.assert_allclose(m.vertices[:, 0].max(), 10.0 + 8.5 * 0.5)
    np.testing.assert_allclose(m.vertices[:, 1].max(), 20.0 - 0.25)
    np.testing.assert_allclose(m.vertices[:, 1].min(), 20.0 - 5.5 * 0.5)
    np.testing.assert_allclose(m.vertices[3 * 9 + 4], [10.0 + 4.5 * 0.5, 20.0 - 3.5 * 0.5, 0.7])
    if ext == ".ply":
        assert np.all(np.asarray(m.visual.vertex_colors)[:, 0] == 128)  # round(0.5 * 255)
    with pytest.raises(ValueError, match="stl"):
        tio.export_mesh(t, tmp_path / "m.stl")


def test_hillshade_of_a_tilted_plane_matches_the_formula(tmp_path):
    # plane rising to the east by 1 m / m: normal (-1, 0, 1)/sqrt 2; sun from the east at 45 deg
    h = np.tile(np.arange(10.0), (8, 1))
    s = tio.hillshade(h, 1.0, azimuth=np.radians(90), elevation=np.radians(45))
    np.testing.assert_allclose(s, 0.0, atol=1e-12)  # rays graze the slope: n . l = 0
    s2 = tio.hillshade(h, 1.0, azimuth=np.radians(270), elevation=np.radians(45))
    np.testing.assert_allclose(s2, 1.0)  # sun in the west: the slope faces it squarely
    flat = tio.hillshade(np.zeros((4, 4)), 1.0, elevation=np.radians(30))
    np.testing.assert_allclose(flat, 0.5)
    t = Terrain(h, np.full(h.shape, 0.1, np.float32), 1.0)
    p = tio.hillshade_png(t, tmp_path / "hs.png")
    assert np.asarray(Image.open(p)).shape == (8, 10)


@pytest.mark.parametrize("ext", [".ply", ".obj"])
def test_mesh_export_reads_as_n_by_3_points_in_trimesh_and_meshio(tmp_path, ext):
    import meshio

    h = np.add.outer(np.arange(5.0), 2 * np.arange(7.0)) * 0.1
    t = Terrain(h, np.full(h.shape, 0.25, np.float32), spacing=0.5, origin=(1.0, 2.0))
    p = tio.export_mesh(t, tmp_path / f"m{ext}")
    tm = trimesh.load(p, process=False)
    assert tm.vertices.shape == (35, 3) and tm.faces.shape == (2 * 4 * 6, 3)
    mm = meshio.read(p)
    assert mm.points.shape == (35, 3)  # a 'v x y z r g b' OBJ read as (n, 6)
    np.testing.assert_allclose(mm.points[1 * 7 + 3], [1.0 + 3.5 * 0.5, 2.0 - 1.5 * 0.5, 0.7])
    assert sum(len(c.data) for c in mm.cells if c.type == "triangle") == 48
    if ext == ".obj":
        lines = [ln for ln in p.read_text().splitlines() if ln.startswith("v ")]
        assert len(lines) == 35 and all(len(ln.split()) == 4 for ln in lines)


def test_albedo_file_is_read_as_the_albedo(tmp_path, terrain):
    alb = Terrain(np.asarray(terrain.albedo, float), terrain.albedo, spacing=1.0)
    tio.save_dem(tmp_path / "alb.npz", alb)
    tio.save_dem(tmp_path / "h.npz", terrain)
    t = tio.load_dem(tmp_path / "h.npz", albedo_file=tmp_path / "alb.npz")
    np.testing.assert_array_equal(t.albedo, terrain.albedo)
