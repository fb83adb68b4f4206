"""GeoTIFF and other GDAL rasters (simlunar.terrain.geotiff, through load_dem / save_dem):
spacing, origin, nodata, CRS and vertical units read; south-up and non-square grids handled or
refused in one line; simlunar's own two-band GeoTIFF and its older tifffile stack."""

import json

import numpy as np
import pytest

from simlunar.terrain import io as tio
from simlunar.terrain.geotiff import LUNAR_CRS, float32_profile


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


def test_float32_profile_is_a_lossless_float_geotiff_without_crs(tmp_path):
    import rasterio

    p = float32_profile((3, 5), count=2, transform=(0.5, 0.0, 10.0, 0.0, -0.5, 20.0))
    assert (p["width"], p["height"], p["count"], p["dtype"]) == (5, 3, 2, "float32")
    assert "crs" not in p and np.isnan(p["nodata"])
    assert tuple(p["transform"])[:6] == (0.5, 0.0, 10.0, 0.0, -0.5, 20.0)
    bands = np.arange(30, dtype=np.float32).reshape(2, 3, 5) / 7
    bands[1, 2, 4] = np.nan
    with rasterio.open(tmp_path / "x.tif", "w", **p) as dst:
        dst.write(bands)
    with rasterio.open(tmp_path / "x.tif") as src:  # deflate + predictor 3 is lossless
        assert src.compression.value == "DEFLATE" and src.crs is None
        np.testing.assert_array_equal(src.read(), bands)
