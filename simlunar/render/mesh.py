"""Mitsuba triangle mesh of a :class:`~simlunar.terrain.Terrain` (the one place that builds it).

Vertices, faces and texture coordinates come from :mod:`simlunar.terrain.mesh` (one vertex
per cell centre, triangles touching nodata cells dropped), so the renderer and mesh export see
the same triangles. Texture coordinates put texel (r, c) of the albedo grid exactly at vertex
(r, c): u = (c + 1/2) / cols, v = (r + 1/2) / rows. Mitsuba's ``bitmap`` texture addresses
row 0 of its data at v = 0 (no flip for meshes built in memory; only its OBJ/PLY loaders flip
v), so the albedo array is handed over unflipped; with ``filter_type: nearest`` every point
of the surface whose nadir projection lies in cell (r, c) gets albedo[r, c]
(tested with a checkerboard in ``tests/render/test_mesh.py``).
"""

from __future__ import annotations

import numpy as np

from simlunar.terrain.mesh import grid_faces, grid_uv, grid_vertices


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
        With ``vertex_positions`` (rows*cols*3), ``faces`` and ``vertex_texcoords``.

    Raises
    ------
    ValueError
        If no triangle survives (every 2x2 block touches nodata).
    """
    from simlunar.render import backend

    mi = backend.mitsuba()
    heights = np.asarray(terrain.heights, float)
    nodata = np.isnan(heights)
    if nodata.all():
        raise ValueError("terrain.heights: every cell is nodata (NaN); nothing to render")
    faces = grid_faces(heights.shape, nodata)
    if len(faces) == 0:
        raise ValueError("terrain.heights: no 2x2 block of valid cells; no triangle to render")
    # unreferenced nodata vertices are kept (index = r * cols + c) but must not poison the
    # bounding box with NaN
    filled = np.where(nodata, np.nanmin(heights), heights)
    verts = grid_vertices(filled, terrain.spacing, terrain.origin)
    uv = grid_uv(heights.shape)
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


def albedo_texture(albedo: np.ndarray) -> dict:
    """``bitmap`` texture dictionary of an albedo grid (rows, cols), nearest, raw, clamped."""
    from simlunar.render import backend

    mi = backend.mitsuba()
    a = np.ascontiguousarray(np.asarray(albedo, np.float32)[..., None])
    return {
        "type": "bitmap",
        "data": mi.TensorXf(a),
        "filter_type": "nearest",
        "raw": True,
        "wrap_mode": "clamp",
    }
