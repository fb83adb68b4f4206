"""LIDAR scan export: LAS/LAZ read back by laspy, PLY, range images, manifest."""

from __future__ import annotations

import json

import numpy as np
import pytest

from simlunar.results.lidar_exports import (
    INTENSITY_MAX,
    intensity_scale,
    scan_angles_deg,
    write_las,
    write_lidar_export,
    write_lidar_ply,
)


def _cloud(n=500, seed=0):
    rng = np.random.default_rng(seed)
    pts = np.c_[rng.uniform(0, 64, n), rng.uniform(-64, 0, n), rng.normal(0, 0.5, n)]
    return pts, rng.uniform(0, 3, n), rng.uniform(0, 1e5, n), rng.integers(1, 4, n)


@pytest.mark.parametrize("suffix", [".las", ".laz"])
def test_las_round_trip(tmp_path, suffix):
    import laspy

    pts, t, ph, ret = _cloud()
    path = write_las(tmp_path / f"c{suffix}", pts, times=t, photons=ph, returns=ret)
    las = laspy.read(path)
    assert las.header.point_format.id == 6 and len(las.points) == len(pts)
    got = np.c_[las.x, las.y, las.z]
    assert np.abs(got - pts).max() <= 0.5e-4 + 1e-9  # the 0.1 mm coordinate scale
    # the time is what it is: seconds from the start, no absolute (GPS) time
    assert np.asarray(las.time_from_start) == pytest.approx(t)
    assert (np.asarray(las.gps_time) == 0).all()
    assert np.asarray(las.photons) == pytest.approx(ph)
    # up to 1e5 photons: scaled by 65535 / max, none clipped, the brightest at the maximum
    k = INTENSITY_MAX / ph.max()
    assert (np.asarray(las.intensity) == np.round(ph * k)).all()
    assert (np.asarray(las.intensity) == INTENSITY_MAX).sum() == 1
    assert (np.asarray(las.number_of_returns) == ret).all()
    assert (np.asarray(las.return_number) == 1).all()


def test_ply_round_trip(tmp_path):
    pts, t, ph, ret = _cloud(50)
    path = write_lidar_ply(tmp_path / "c.ply", pts, times=t, photons=ph, returns=ret)
    blob = path.read_bytes()
    head, body = blob.split(b"end_header\n", 1)
    assert b"element vertex 50" in head
    rec = np.frombuffer(body, dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("time", "<f8"),
                                     ("photons", "<f4"), ("returns", "u1")])  # fmt: skip
    assert np.c_[rec["x"], rec["y"], rec["z"]] == pytest.approx(pts)
    assert rec["time"] == pytest.approx(t) and (rec["returns"] == ret).all()


def test_export_folder_and_completeness(tmp_path):
    from simlunar.imaging.exr import read_exr
    from simlunar.results.exports import export_complete

    pts, t, ph, ret = _cloud(20)
    img = np.full((8, 8), np.nan, np.float32)
    img[2, 3] = 51.0
    payload = {
        "kind": "lidar",
        "labels": {
            "wavelet": {"points": pts, "times": t, "photons": ph, "returns": ret,
                        "images": {"range": img, "depth": img, "photons": img}, "seconds": 1.5}
        },
    }  # fmt: skip
    folder = write_lidar_export(tmp_path / "unit0", payload, unit_key="abc")
    m = json.loads((folder / "manifest.json").read_text())
    assert m["files"] == ["wavelet.laz", "wavelet.ply", "wavelet_range.exr", "manifest.json"]
    assert m["points"] == {"wavelet": 20} and "z up" in m["frame"]
    assert read_exr(folder / "wavelet_range.exr")["range"][2, 3] == 51.0
    assert export_complete(folder, "abc") and not export_complete(folder, "other")
    (folder / "wavelet.ply").unlink()
    assert not export_complete(folder, "abc")


def test_intensity_scale_by_hand():
    assert intensity_scale([0.0, 12.0, 65535.0]) == 1.0  # in range: photons as they are
    assert intensity_scale([2.5e6, 10.0]) == pytest.approx(65535 / 2.5e6)
    assert intensity_scale([]) == 1.0 and intensity_scale([np.nan, 3.0]) == 1.0


def test_a_linear_apd_s_photoelectrons_are_not_clipped(tmp_path):
    # a descent's APD returns reach millions of photoelectrons: before the scale 99.7 % of
    # the points clipped at 65535 and their brightness was lost
    import laspy

    pts, t, _, ret = _cloud(1000)
    ph = np.random.default_rng(3).uniform(1e5, 2.5e6, len(pts))
    las = laspy.read(write_las(tmp_path / "c.las", pts, times=t, photons=ph, returns=ret))
    i = np.asarray(las.intensity)
    assert (i == INTENSITY_MAX).mean() < 0.01
    # the brightness keeps its order and proportion (a linear scale, up to the rounding)
    assert np.corrcoef(i, ph)[0, 1] > 0.9999
    scale = next(v for v in las.vlrs if v.user_id == "simlunar")
    assert float(bytes(scale.record_data).decode().split("=")[1]) == pytest.approx(65535 / ph.max())


def test_scan_angle_and_origin_per_point(tmp_path):
    import laspy

    origin = np.array([1.0, 2.0, 10.0])
    # straight down, 45 deg towards +x, 30 deg towards -x, 45 deg towards +y (x = 0: unsigned)
    pts = origin + np.array([[0, 0, -10], [10, 0, -10], [-np.tan(np.radians(30)) * 10, 0, -10],
                             [0, 10, -10]])  # fmt: skip
    assert scan_angles_deg(pts, origin) == pytest.approx([0.0, 45.0, -30.0, 45.0])
    path = write_las(tmp_path / "c.laz", pts, times=np.zeros(4), photons=np.ones(4),
                     returns=np.ones(4, int), origins=origin)  # fmt: skip
    las = laspy.read(path)
    # LAS 1.4 scan angle: 0.006 deg units
    assert np.asarray(las.scan_angle) * 0.006 == pytest.approx([0.0, 45.0, -30.0, 45.0], abs=0.006)
    got = np.c_[las.origin_x, las.origin_y, las.origin_z]
    assert np.allclose(got, origin)


def test_the_terrain_s_crs_is_written_and_a_local_frame_writes_none(tmp_path):
    import laspy

    wkt = (
        'PROJCS["Moon_Polar_Stereographic",GEOGCS["Moon 2000",DATUM["D_Moon_2000",'
        'SPHEROID["Moon_2000_IAU_IAG",1737400.0,0.0]],PRIMEM["Greenwich",0],'
        'UNIT["Decimal_Degree",0.0174532925199433]],PROJECTION["Stereographic"],UNIT["Meter",1]]'
    )
    pts, t, ph, ret = _cloud(10)
    las = laspy.read(write_las(tmp_path / "g.las", pts, times=t, photons=ph, returns=ret, crs=wkt))
    rec = [v for v in las.header.vlrs if v.record_id == 2112]
    assert len(rec) == 1 and rec[0].string.strip("\x00") == wkt
    assert las.header.global_encoding.wkt
    local = laspy.read(write_las(tmp_path / "l.las", pts, times=t, photons=ph, returns=ret))
    assert not [v for v in local.header.vlrs if v.record_id == 2112]


def test_the_payload_carries_the_terrain_s_crs_and_the_sensor_origin():
    # the unit hands the payload the terrain's CRS as its fourth argument
    from types import SimpleNamespace

    from simlunar.geometry import Camera, Intrinsics, Pose
    from simlunar.results.lidar_exports import lidar_export_payload

    cam = Camera(Intrinsics.from_fov(8, 8, 40.0), Pose.look_at((0.0, 0.0, 10.0), (0.0, 0.0, 0.0)))
    scan = SimpleNamespace(valid=np.array([True, False]), points=np.array([[1.0, 0, 0], [0, 0, 0]]),
                           times=None, returns=None, photons=np.array([5.0, 0.0]))  # fmt: skip
    # the acquisition's planned cells and values are those of its valid points
    acq = SimpleNamespace(detail=scan, rc=np.array([[1, 1]]), values=np.array([9.0]), seconds=0.5)
    payload = lidar_export_payload({"grid": acq}, cam, (8, 8), 'LOCAL_CS["moon"]')
    assert payload["crs"] == 'LOCAL_CS["moon"]'
    assert payload["labels"]["grid"]["origin"] == pytest.approx([0.0, 0.0, 10.0])
    assert len(payload["labels"]["grid"]["points"]) == 1
