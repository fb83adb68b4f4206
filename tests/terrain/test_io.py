"""DEM round trips, foreign DEMs, bad files, mesh export, hillshade."""

import json

import numpy as np
import pytest
import trimesh
from PIL import Image

from simlunar.terrain import Terrain
from simlunar.terrain import io as tio
from simlunar.terrain.geotiff import LUNAR_CRS


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


def test_foreign_geotiff_loads_spacing_origin_nodata_and_crs(tmp_path):
    import rasterio
    from rasterio.crs import CRS
    from rasterio.transform import Affine

    z = np.arange(12 * 9, dtype=np.float32).reshape(12, 9)
    z[2, 3] = -9999
    z[11, 8] = -9999
    crs = CRS.from_string("IAU_2015:30110")
    with rasterio.open(
        tmp_path / "lola.tif", "w", driver="GTiff", width=9, height=12, count=1,
        dtype="float32", crs=crs, transform=Affine(5.0, 0, 1000.0, 0, -5.0, 2000.0), nodata=-9999,
    ) as dst:  # fmt: skip
        dst.write(z, 1)
    t = tio.load_dem(tmp_path / "lola.tif")
    assert t.spacing == 5.0 and t.origin == (1000.0, 2000.0)
    assert t.shape == (12, 9) and t.nodata.sum() == 2
    assert np.isnan(t.heights[2, 3]) and np.isnan(t.heights[11, 8])
    assert t.heights[0, 1] == 1.0 and t.heights[5, 4] == 5 * 9 + 4
    assert CRS.from_wkt(t.crs) == crs
    # the centre of cell (r, c) is the GeoTIFF transform applied to pixel (c + 1/2, r + 1/2)
    x, y = t.cell_centers()
    with rasterio.open(tmp_path / "lola.tif") as src:
        assert src.transform @ (4.5, 7.5) == (x[4], y[7]) == (1022.5, 1962.5)


def test_geotiff_vertical_units_scale_and_south_up(tmp_path):
    import rasterio
    from rasterio.transform import Affine

    z = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]], np.float32)
    with rasterio.open(
        tmp_path / "km.tif", "w", driver="GTiff", width=2, height=3, count=1,
        dtype="float32", transform=Affine(2.0, 0, 10.0, 0, 2.0, 20.0),
    ) as dst:  # fmt: skip
        dst.write(z, 1)
        dst.units = ("km",)
        dst.scales = (0.5,)
        dst.offsets = (1.0,)
    t = tio.load_dem(tmp_path / "km.tif")
    # south-up (positive row step): rows flip, the top edge is at y = 20 + 3 * 2
    assert t.origin == (10.0, 26.0) and t.spacing == 2.0
    np.testing.assert_array_equal(t.heights, (z[::-1] * 0.5 + 1.0) * 1000.0)


def test_geotiff_refusals_are_one_line_naming_the_file(tmp_path):
    import rasterio
    from rasterio.crs import CRS
    from rasterio.transform import Affine

    def write(name, transform, crs=None):
        with rasterio.open(
            tmp_path / name, "w", driver="GTiff", width=4, height=4, count=1,
            dtype="float32", transform=transform, crs=crs,
        ) as dst:  # fmt: skip
            dst.write(np.add.outer(np.arange(4.0), np.arange(4.0)).astype(np.float32), 1)
        return tmp_path / name

    p = write("rot.tif", Affine(1.0, 0.2, 0, 0.2, -1.0, 0))
    with pytest.raises(ValueError, match=r"rot\.tif: rotated"):
        tio.load_dem(p)
    p = write("geo.tif", Affine(0.01, 0, 0, 0, -0.01, 0), CRS.from_string("IAU_2015:30100"))
    with pytest.raises(ValueError, match=r"geo\.tif: .*geographic"):
        tio.load_dem(p)
    p = write("rect.tif", Affine(2.0, 0, 0, 0, -1.0, 0))
    with pytest.raises(ValueError, match=r"rect\.tif: non-square pixels 2\.0 x 1\.0"):
        tio.load_dem(p)
    t = tio.load_dem(p, resample=True)  # to 1 m cells: 4 x 8
    assert t.spacing == 1.0 and t.shape == (4, 8)
    # the plane z = r + c (in source pixels) is still a plane: rises 1 per row, 1/2 per new col
    np.testing.assert_allclose(np.diff(t.heights[:, 2:6], axis=1), 0.5, atol=1e-6)


def test_generated_terrain_geotiff_reads_back_in_rasterio(tmp_path):
    import rasterio
    from rasterio.crs import CRS
    from rasterio.transform import Affine

    from simlunar.config.translate import preset_params
    from simlunar.terrain import generate

    res = generate(preset_params("aerial_3"), rng=1, scale=0.05)
    t = res.terrain
    p = tio.save_dem(tmp_path / "dem.tif", t)
    with rasterio.open(p) as src:
        assert src.count == 2 and src.descriptions == ("height", "albedo")
        assert src.res == (t.spacing, t.spacing)
        assert src.transform == Affine(t.spacing, 0, t.origin[0], 0, -t.spacing, t.origin[1])
        assert src.crs == CRS.from_string(LUNAR_CRS) and src.crs.linear_units == "metre"
        assert src.units[0] == "m"
        np.testing.assert_array_equal(src.read(1), t.heights.astype(np.float32))
        np.testing.assert_array_equal(src.read(2), t.albedo)
    back = tio.load_dem(p)
    assert CRS.from_wkt(back.crs) == CRS.from_string(LUNAR_CRS)
    # a loaded CRS is carried to the next file (GeoTIFF and npz)
    q = tio.save_dem(tmp_path / "again.tif", back)
    with rasterio.open(q) as src:
        assert src.crs == CRS.from_string(LUNAR_CRS)
    assert tio.load_dem(tio.save_dem(tmp_path / "a.npz", back)).crs == back.crs


def test_albedo_file_is_read_as_the_albedo(tmp_path, terrain):
    alb = Terrain(np.asarray(terrain.albedo, float), terrain.albedo, spacing=1.0)
    tio.save_dem(tmp_path / "alb.npz", alb)
    tio.save_dem(tmp_path / "h.npz", terrain)
    t = tio.load_dem(tmp_path / "h.npz", albedo_file=tmp_path / "alb.npz")
    np.testing.assert_array_equal(t.albedo, terrain.albedo)


def test_other_gdal_formats_load_with_their_transform(tmp_path):
    import rasterio
    from rasterio.transform import Affine

    z = np.add.outer(np.arange(6.0), np.arange(7.0)).astype(np.float32)
    with rasterio.open(
        tmp_path / "dtm.img", "w", driver="HFA", width=7, height=6, count=1,
        dtype="float32", transform=Affine(2.0, 0, -50.0, 0, -2.0, 30.0), nodata=-3.4e38,
    ) as dst:  # fmt: skip
        dst.write(z, 1)
    t = tio.load_dem(tmp_path / "dtm.img")
    assert t.spacing == 2.0 and t.origin == (-50.0, 30.0)
    np.testing.assert_array_equal(t.heights, z)


def test_pre_geotiff_simlunar_tif_still_loads(tmp_path):
    # simlunar wrote .tif with tifffile before: a 2-page stack with JSON meta in the description
    import tifffile

    h = np.arange(12, dtype=np.float32).reshape(3, 4)
    a = np.full((3, 4), 0.3, np.float32)
    meta = {"spacing": 0.25, "origin": [1.0, 2.0], "format": "simlunar-dem-1"}
    tifffile.imwrite(
        tmp_path / "old.tif",
        np.stack([h, a]),
        photometric="minisblack",
        metadata={"simlunar": json.dumps(meta)},
    )
    t = tio.load_dem(tmp_path / "old.tif")
    assert t.spacing == 0.25 and t.origin == (1.0, 2.0)
    np.testing.assert_array_equal(t.heights, h)
    np.testing.assert_array_equal(t.albedo, a)
