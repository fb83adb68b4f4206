"""The terrain mesh in Mitsuba: vertices at cell centres, albedo texels on cells (no v flip)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import OrthoCamera
from simlunar.render.lights import CameraLight
from simlunar.render.mesh import terrain_mesh
from simlunar.render.scene import TerrainScene
from simlunar.terrain.types import Terrain

pytestmark = pytest.mark.render


def test_mesh_buffers_match_grid(mi):
    h = np.arange(12.0).reshape(3, 4)
    h[2, 3] = np.nan
    t = Terrain(h, np.zeros((3, 4), np.float32), 0.5, origin=(1.0, 2.0))
    mesh = terrain_mesh(t)
    params = mi.traverse(mesh)
    v = np.array(params["vertex_positions"]).reshape(-1, 3)
    f = np.array(params["faces"]).reshape(-1, 3)
    uv = np.array(params["vertex_texcoords"]).reshape(-1, 2)
    # the 3 x 4 grid plus the skirt ring: 5 x 6 vertices, cell (r, c) at (r + 1) * 6 + c + 1
    assert v.shape == (30, 3)
    # cell (1, 2): x = 1 + 2.5 * 0.5, y = 2 - 1.5 * 0.5, z = h[1, 2]
    np.testing.assert_allclose(v[2 * 6 + 3], [2.25, 1.25, 6.0])
    # skirt corner (-1, -1): on the grid's outer corner (1, 2), with cell (0, 0)'s height
    np.testing.assert_allclose(v[0], [1.0, 2.0, 0.0])
    # 2 * (4 * 5) triangles minus those touching the NaN corner cell (2, 3) and the 3 skirt
    # vertices that replicate it (padded (3, 4), (3, 5), (4, 4), (4, 5)): 1 + 2 + 2 + 1 + ...
    bad = [3 * 6 + 4, 3 * 6 + 5, 4 * 6 + 4, 4 * 6 + 5]
    assert not np.isin(bad, f).any()
    assert f.shape == (40 - 7, 3)
    np.testing.assert_allclose(uv[2 * 6 + 3], [2.5 / 4, 1.5 / 3])
    np.testing.assert_allclose(uv[0], [-0.5 / 4, -0.5 / 3])  # clamped to texel (0, 0)
    assert np.isfinite(v).all()  # the unreferenced nodata vertices must not poison the bbox


@pytest.mark.parametrize("shape", [(6, 8), (7, 5)])
def test_albedo_grid_appears_cell_for_cell(mi, shape):
    # a checkerboard of random albedos: a checkerboard alone survives some flips, random
    # values catch any permutation of rows or columns (e.g. Mitsuba's v flip)
    rng = np.random.default_rng(7)
    checker = (np.indices(shape).sum(0) % 2).astype(np.float32)
    albedo = (0.1 + 0.5 * checker + 0.3 * rng.random(shape)).astype(np.float32)
    t = Terrain(np.zeros(shape), albedo, 0.2, origin=(3.0, -1.0))
    cam = OrthoCamera.nadir_for_grid(shape, 0.2, t.origin, altitude=4.0)
    img = TerrainScene(t, cam, lights=[CameraLight(np.pi)], max_depth=2, spp=16).render()
    # directional light along the view, irradiance pi: radiance = albedo exactly
    # the skirt covers the border pixels fully (no dark frame) with their own cell's texel
    np.testing.assert_allclose(img[..., 0], albedo, rtol=1e-5)
