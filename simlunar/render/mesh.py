"""Mitsuba triangle mesh of a :class:`~simlunar.terrain.Terrain` (the one place that builds it).

Vertices, faces and texture coordinates come from :mod:`simlunar.terrain.mesh` (one vertex
per cell centre, triangles touching nodata cells dropped), so the renderer and mesh export see
the same triangles. Texture coordinates put texel (r, c) of the albedo grid exactly at vertex
(r, c): u = (c + 1/2) / cols, v = (r + 1/2) / rows. Mitsuba's ``bitmap`` texture addresses
row 0 of its data at v = 0 (no flip for meshes built in memory; only its OBJ/PLY loaders flip
v), so the albedo array is handed over unflipped; with ``filter_type: nearest`` every point
of the surface whose nadir projection lies in cell (r, c) gets albedo[r, c]
(tested with a checkerboard in ``tests/render/test_mesh.py``).

The rendered mesh adds a one-cell skirt: a ring of vertices half a cell outside the outer cell
centres, i.e. on the grid's outer cell edges, with the edge cells' heights (and texture
coordinates extrapolated, which the clamped texture maps to the edge texels). Without it the
mesh would end at the outer cell centres, so a nadir view's border pixels would be half
terrain, half void: a dark one-pixel frame that every image feature (gradient, entropy,
wavelet) fires on. With it every pixel of ``OrthoCamera.nadir_for_grid`` sees only its cell.
"""

from __future__ import annotations

import numpy as np

from simlunar.render import backend
from simlunar.terrain.mesh import grid_faces, grid_vertices

__all__ = ["albedo_texture", "grid_texture", "terrain_mesh"]


def terrain_mesh(terrain, *, name: str = "terrain", bsdf=None):
    """Build the ``mi.Mesh`` of ``terrain`` (flat-shaded: no vertex normals).

    Parameters
    ----------
    terrain : Terrain
        Heights (NaN = nodata), spacing and origin.
    name : str
        Mesh name (Mitsuba id).
    bsdf : mi.BSDF or None
        BSDF object to attach (Mitsuba's default diffuse when None).

    Returns
    -------
    mi.Mesh
        With ``vertex_positions`` ((rows+2)*(cols+2)*3: the grid plus the skirt ring; cell
        (r, c) is vertex (r + 1) * (cols + 2) + c + 1), ``faces`` and ``vertex_texcoords``.

    Raises
    ------
    ValueError
        If no triangle survives (every 2x2 block touches nodata).
    """

    mi = backend.mitsuba()
    heights = np.asarray(terrain.heights, float)
    nodata = np.isnan(heights)
    if nodata.all():
        raise ValueError("terrain.heights: every cell is nodata (NaN); nothing to render")
    ok = ~nodata
    if not (ok[:-1, :-1] & ok[1:, :-1] & ok[:-1, 1:] & ok[1:, 1:]).any():
        raise ValueError("terrain.heights: no 2x2 block of valid cells; no triangle to render")
    rows, cols = heights.shape
    s = terrain.spacing
    padded = np.pad(heights, 1, mode="edge")  # the skirt ring (see module docstring)
    pad_nodata = np.isnan(padded)
    faces = grid_faces(padded.shape, pad_nodata)
    # unreferenced nodata vertices are kept but must not poison the bounding box with NaN
    filled = np.where(pad_nodata, np.nanmin(heights), padded)
    x0, y0 = terrain.origin
    verts = grid_vertices(filled, s, (x0 - s, y0 + s))
    # the ring sits on the outer cell edges, half a cell outside the outer cell centres
    verts[:, 0] = np.clip(verts[:, 0], x0, x0 + cols * s)
    verts[:, 1] = np.clip(verts[:, 1], y0 - rows * s, y0)
    # texel (r, c) at cell (r, c): u = (c + 1/2) / cols for c = -1 .. cols (clamped outside)
    u = (np.arange(-1, cols + 1) + 0.5) / cols
    v = (np.arange(-1, rows + 1) + 0.5) / rows
    U, V = np.meshgrid(u, v)
    uv = np.stack([U.ravel(), V.ravel()], axis=1)
    props = mi.Properties()
    if bsdf is not None:
        props["bsdf"] = bsdf
    mesh = mi.Mesh(
        name,
        len(verts),
        len(faces),
        props=props,
        has_vertex_normals=False,
        has_vertex_texcoords=True,
    )
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(verts.astype(np.float32).ravel())
    params["faces"] = mi.UInt32(faces.astype(np.uint32).ravel())
    params["vertex_texcoords"] = mi.Float(uv.astype(np.float32).ravel())
    params.update()
    return mesh


def grid_texture(values: np.ndarray) -> dict:
    """``bitmap`` texture dictionary of a per-cell grid (rows, cols): nearest, raw, clamped.

    With the terrain UVs every surface point whose nadir projection lies in cell (r, c) reads
    ``values[r, c]`` (albedo, Oren-Nayar roughness, ...).
    """

    mi = backend.mitsuba()
    a = np.ascontiguousarray(np.asarray(values, np.float32)[..., None])
    return {
        "type": "bitmap",
        "data": mi.TensorXf(a),
        "filter_type": "nearest",
        "raw": True,
        "wrap_mode": "clamp",
    }


def albedo_texture(albedo: np.ndarray) -> dict:
    """``bitmap`` texture dictionary of an albedo grid (rows, cols), nearest, raw, clamped."""
    return grid_texture(albedo)
