"""How every coded scan ends: its decode triangulated into a cloud and a guide-view depth, and
bundled with the sensed frames."""

from __future__ import annotations

import numpy as np

from simlunar.scanner import rigs
from simlunar.scanner.gray_code import GrayCodeOptions, gray_code_scan
from simlunar.scanner.result import CodedScan, coded_scan, triangulated
from tests.scanner._synthetic import PlaneCapture


def test_coded_scan_triangulates_with_the_codings_method_and_keeps_the_frames():
    rig = rigs.moonyard_rig(proj_size=(32, 24), cam_size=(64, 48))
    cap = PlaneCapture(rig, (0.1, 0.0, 1.0), 0.0)
    scan = gray_code_scan(cap, rig, GrayCodeOptions(black_threshold=0.2, keep_frames=True))
    white, black = scan.frames["white"], scan.frames["black"]
    assert scan.frames["images"].shape == (2 * (5 + 5), 48, 64)
    again = coded_scan(rig, scan.decode, white, black, None, renders=7, coding=scan.coding)
    assert isinstance(again, CodedScan) and again.renders == 7
    assert set(again.frames) == {"white", "black"} and again.coding is scan.coding
    np.testing.assert_array_equal(again.depth, scan.depth)
    cloud, depth = triangulated(rig, scan.decode, "plane")
    np.testing.assert_array_equal(depth, scan.depth)
    assert len(cloud.points) == int(scan.decode.valid.sum())
    # rays use the decoded row too: another estimate of the same plane, not the same numbers
    _cloud, rays = triangulated(rig, scan.decode, "rays")
    ok = np.isfinite(rays) & np.isfinite(depth)
    assert ok.mean() > 0.5 and not np.array_equal(rays[ok], depth[ok])
    np.testing.assert_allclose(rays[ok], depth[ok], rtol=0.05)
