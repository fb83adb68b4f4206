import numpy as np

from simlunar.terrain.mesh import grid_faces, grid_uv, grid_vertices


def test_grid_mesh_counts_orientation_and_positions():
    h = np.arange(12.0).reshape(3, 4)
    v = grid_vertices(h, 0.5, origin=(1.0, 2.0))
    f = grid_faces(h.shape)
    assert v.shape == (12, 3) and f.shape == (2 * 2 * 3, 3)
    np.testing.assert_allclose(v[1 * 4 + 2], [1.0 + 2.5 * 0.5, 2.0 - 1.5 * 0.5, 6.0])
    # every face is counter-clockwise seen from +z (positive signed area), on a flat grid
    flat = grid_vertices(np.zeros((3, 4)), 0.5)
    p = flat[f]
    area = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 2]
    assert np.all(area > 0)
    np.testing.assert_allclose(area.sum() / 2, (3 - 1) * (4 - 1) * 0.25)


def test_nodata_cells_drop_their_triangles():
    nod = np.zeros((3, 3), bool)
    nod[1, 1] = True  # the centre cell is a vertex of 6 of the 8 triangles (one diagonal)
    assert len(grid_faces((3, 3), nod)) == 2
    nod[:] = False
    nod[0, 0] = True
    assert len(grid_faces((3, 3), nod)) == 8 - 1


def test_uv_hits_texel_centres():
    uv = grid_uv((2, 4))
    np.testing.assert_allclose(uv[4 + 3], [3.5 / 4, 1.5 / 2])
