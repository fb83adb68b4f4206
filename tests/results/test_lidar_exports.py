"""LIDAR scan export: LAS/LAZ read back by laspy, PLY, range images, manifest."""

from __future__ import annotations

import json

import numpy as np
import pytest

from simlunar.results.lidar_exports import write_las, write_lidar_export, write_lidar_ply


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
    assert np.asarray(las.gps_time) == pytest.approx(t)
    assert np.asarray(las.photons) == pytest.approx(ph)
    assert (np.asarray(las.intensity) == np.clip(np.round(ph), 0, 65535)).all()
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
