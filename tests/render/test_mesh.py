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
    assert v.shape == (12, 3)
    # cell (1, 2): x = 1 + 2.5 * 0.5, y = 2 - 1.5 * 0.5, z = h[1, 2]
    np.testing.assert_allclose(v[1 * 4 + 2], [2.25, 1.25, 6.0])
    # 2 * (2 * 3) triangles minus the one touching the NaN corner cell
    assert f.shape == (11, 3)
    assert not np.isin(11, f)
    np.testing.assert_allclose(uv[1 * 4 + 2], [2.5 / 4, 1.5 / 3])
    assert np.isfinite(v).all()  # the unreferenced nodata vertex must not poison the bbox


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
    np.testing.assert_allclose(img[1:-1, 1:-1, 0], albedo[1:-1, 1:-1], rtol=1e-5)
    # border pixels are half covered (the mesh ends at the cell centres) but only by their
    # own cell's texel: 0 < L <= albedo
    edge = np.ones(shape, bool)
    edge[1:-1, 1:-1] = False
    assert np.all(img[edge, 0] > 0) and np.all(img[edge, 0] <= albedo[edge] * (1 + 1e-5))
