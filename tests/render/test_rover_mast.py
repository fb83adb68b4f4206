"""Rover-mast viewpoints: pose conventions, and the oblique ground truth against an
independent NumPy ray-march of the DEM's triangle mesh."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Intrinsics, Pose, grid_height_at, rover_mast_camera
from simlunar.render.lights import SunLight
from simlunar.render.scene import TerrainScene
from simlunar.terrain.types import Terrain


def test_heading_pose_axes():
    p = Pose.from_heading((0, 0, 2), azimuth_deg=90, depression_deg=30)  # looking east
    np.testing.assert_allclose(p.forward, [np.cos(np.radians(30)), 0, -0.5], atol=1e-12)
    np.testing.assert_allclose(p.rotation[:, 0], [0, -1, 0], atol=1e-12)  # right = south
    assert p.rotation[2, 1] < 0  # image down has a downward world component
    # a point straight ahead on the axis projects to the principal point
    cam = rover_mast_camera(np.zeros((20, 20)), 1.0, depression_deg=45, azimuth_deg=0)
    uv, z = cam.project(cam.position + 3.0 * cam.pose.forward)
    np.testing.assert_allclose(uv, [160, 120]) and np.testing.assert_allclose(z, 3.0)
    # mast foot at the grid centre, 1.5 m above the ground there
    np.testing.assert_allclose(cam.position, [10, -10, 1.5])


def test_grid_height_at_is_bilinear_between_cell_centres():
    h = np.add.outer(2 * np.arange(4.0), np.arange(5.0))  # z = 2 r + c
    assert grid_height_at(h, 1.0, (0, 0), 1.5, -0.5) == pytest.approx(1.0)
    assert grid_height_at(h, 1.0, (0, 0), 2.25, -1.75) == pytest.approx(2 * 1.25 + 1.75)
    with pytest.raises(ValueError, match="outside"):
        grid_height_at(h, 1.0, (0, 0), 0.2, -0.5)


def _mesh_height(h, spacing, origin, x, y):
    """Height of the renderer's triangle mesh (diagonal NE-SW, simlunar.terrain.mesh) at (x, y)."""
    fc = (x - origin[0]) / spacing - 0.5
    fr = (origin[1] - y) / spacing - 0.5
    rows, cols = h.shape
    inside = (fc >= 0) & (fc <= cols - 1) & (fr >= 0) & (fr <= rows - 1)
    c0 = np.clip(np.floor(fc).astype(int), 0, cols - 2)
    r0 = np.clip(np.floor(fr).astype(int), 0, rows - 2)
    tc, tr = fc - c0, fr - r0
    za, zb = h[r0, c0], h[r0, c0 + 1]  # NW, NE
    zc, zd = h[r0 + 1, c0], h[r0 + 1, c0 + 1]  # SW, SE
    upper = tc + tr <= 1  # triangle (NW, SW, NE)
    z = np.where(
        upper,
        za + tc * (zb - za) + tr * (zc - za),
        zd + (1 - tc) * (zc - zd) + (1 - tr) * (zb - zd),
    )
    return np.where(inside, z, np.nan)


def _ray_march(h, spacing, origin, o, d, t_max):
    """First crossing of rays o + t d (n, 3) below the mesh: march, then bisect."""
    n = len(o)
    t_hit = np.full(n, np.nan)
    step = spacing / 8
    ts = np.arange(step, t_max, step)
    prev = np.zeros(n)
    found = np.zeros(n, bool)
    for t in ts:
        p = o + t * d
        below = (p[:, 2] < _mesh_height(h, spacing, origin, p[:, 0], p[:, 1])) & ~found
        for i in np.flatnonzero(below):
            lo, hi = prev[i], t
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                q = o[i] + mid * d[i]
                zs = _mesh_height(h, spacing, origin, q[None, 0], q[None, 1])[0]
                lo, hi = (mid, hi) if q[2] > zs else (lo, mid)
            t_hit[i] = 0.5 * (lo + hi)
        found |= below
        prev[:] = t
    return t_hit


@pytest.mark.parametrize("depression", [30.0, 60.0])
def test_oblique_ground_truth_matches_a_numpy_ray_cast_of_the_dem(mi, depression):
    rows, cols, sp = 80, 80, 0.1
    r, c = np.mgrid[0:rows, 0:cols] * sp
    h = (
        0.15 * np.sin(c / 1.3) * np.cos(r / 0.9)
        + 0.05 * c
        + 0.4 * np.exp(-((c - 5.0) ** 2 + (r - 2.5) ** 2) / 0.5)
    )  # waves, a tilt and a mound in front of the camera
    t = Terrain(h, np.full(h.shape, 0.15, np.float32), sp, origin=(2.0, 3.0))
    cam = rover_mast_camera(
        t.heights, sp, t.origin, site=(6.0, -3.5), height_above=1.5,
        depression_deg=depression, azimuth_deg=20.0, intrinsics=Intrinsics.from_fov(48, 36, 60.0),
    )  # fmt: skip
    gt = TerrainScene(t, cam, lights=[SunLight(np.radians(40), 0.3)], spp=1).ground_truth()
    rng = np.random.default_rng(5)
    idx = rng.choice(gt.depth.size, 120, replace=False)
    rr, cc = np.unravel_index(idx, gt.depth.shape)
    o, d = cam.rays(np.stack([cc + 0.5, rr + 0.5], axis=1))
    t_hit = _ray_march(t.heights, sp, t.origin, o, d, t_max=20.0)
    ok = np.isfinite(t_hit)
    assert ok.sum() >= 60  # most sampled pixels see the terrain
    np.testing.assert_array_equal(gt.valid[rr, cc], ok)
    depth_ref = (t_hit[:, None] * d) @ cam.pose.forward
    np.testing.assert_allclose(gt.depth[rr, cc][ok], depth_ref[ok], rtol=2e-5, atol=2e-5)
    # the depth is the z-depth in the camera frame, not a height: it grows with range
    assert np.ptp(gt.depth[gt.valid]) > 0.5
