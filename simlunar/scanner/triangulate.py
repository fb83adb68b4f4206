"""Triangulation of camera/projector correspondences, epipolar geometry, depth resampling.

Conventions are those of :mod:`simlunar.geometry.camera`: pixel centres at ``i + 0.5``, poses
camera-to-world, OpenCV device frames. Everything is float64 NumPy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Camera, Projector, Rig


def _ro(a, dtype=np.float64) -> np.ndarray:
    arr = np.array(a, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Correspondences:
    """Sparse camera-pixel to projector-pixel matches.

    Attributes
    ----------
    cam_uv : (n, 2) float64
        Camera pixel coordinates (u, v) (pixel centre of (r, c) is (c + .5, r + .5)).
    proj_uv : (n, 2) float64
        Projector pixel coordinates (u, v). A column-only match has NaN v.
    """

    cam_uv: np.ndarray
    proj_uv: np.ndarray

    def __post_init__(self) -> None:
        cam = _ro(self.cam_uv).reshape(-1, 2)
        proj = _ro(self.proj_uv).reshape(-1, 2)
        if cam.shape != proj.shape:
            raise ValueError(f"cam_uv {cam.shape} and proj_uv {proj.shape} must both be (n, 2)")
        object.__setattr__(self, "cam_uv", cam)
        object.__setattr__(self, "proj_uv", proj)

    def __len__(self) -> int:
        return self.cam_uv.shape[0]

    @classmethod
    def from_gray(cls, result) -> Correspondences:
        """Valid pixels of a :class:`~simlunar.scanner.gray_code.GrayDecode`.

        Projector coordinates are pixel centres, or the sub-pixel stripe-edge refinement where
        the decode has one (:meth:`GrayDecode.proj_uv`).
        """
        r, c = np.nonzero(result.valid)
        cam = np.stack([c + 0.5, r + 0.5], axis=-1)
        return cls(cam, result.proj_uv()[r, c])


@dataclass(frozen=True, eq=False)
class PointCloud:
    """Triangulated points with the projector pixel each came from.

    Attributes
    ----------
    points : (n, 3) float64
        World positions (m).
    proj_uv : (n, 2) float64
        Projector pixel coordinates of each point's correspondence.
    residual : (n,) float64
        Closest-approach distance of the two rays (m); 0 for ray-plane triangulation.
    """

    points: np.ndarray
    proj_uv: np.ndarray
    residual: np.ndarray

    def __post_init__(self) -> None:
        p = _ro(self.points).reshape(-1, 3)
        object.__setattr__(self, "points", p)
        object.__setattr__(self, "proj_uv", _ro(self.proj_uv).reshape(-1, 2))
        object.__setattr__(self, "residual", _ro(self.residual).reshape(-1))
        if not (len(self.proj_uv) == len(p) == len(self.residual)):
            raise ValueError("points, proj_uv and residual must have the same length")

    def __len__(self) -> int:
        return self.points.shape[0]

    @classmethod
    def concatenate(cls, clouds) -> PointCloud:
        clouds = list(clouds)
        if not clouds:
            return cls(np.empty((0, 3)), np.empty((0, 2)), np.empty(0))
        return cls(
            np.concatenate([c.points for c in clouds]),
            np.concatenate([c.proj_uv for c in clouds]),
            np.concatenate([c.residual for c in clouds]),
        )


def check_rig(rig: Rig) -> None:
    """Raise ValueError for a rig that cannot triangulate (zero baseline, off-centre projector)."""
    if not isinstance(rig.projector, Projector):
        raise ValueError("rig.projector must be a geometry.Projector")
    if not rig.projector.intrinsics.is_centred:
        raise ValueError(
            "rig.projector principal point must be centred (Mitsuba's projector "
            "emitter cannot shift it)"
        )
    if rig.baseline < 1e-9:
        raise ValueError(
            "rig baseline is zero: the triangulation camera must be offset from the projector"
        )


def column_planes(projector: Camera, u) -> tuple[np.ndarray, np.ndarray]:
    """World planes swept by projector columns at pixel coordinate ``u``.

    The plane contains the projector centre and every device point with
    ``x / z = (u - cx) / fx``, so its device normal is ``(1, 0, -(u - cx) / fx)``.

    Returns
    -------
    normals : (..., 3) unit world normals
    offsets : (...) plane offsets ``d`` with ``n . X = d``
    """
    a = (np.asarray(u, float) - projector.intrinsics.cx) / projector.intrinsics.fx
    n_dev = np.stack([np.ones_like(a), np.zeros_like(a), -a], axis=-1)
    n_dev /= np.linalg.norm(n_dev, axis=-1, keepdims=True)
    n = n_dev @ projector.pose.rotation.T
    return n, n @ projector.position


def triangulate_plane(rig: Rig, cam_uv, proj_u) -> np.ndarray:
    """Intersect camera rays with projector column planes.

    Parameters
    ----------
    rig : Rig
    cam_uv : (..., 2) camera pixel coordinates
    proj_u : (...) projector column coordinates (u, pixel centres at c + 0.5)

    Returns
    -------
    (..., 3) world points; NaN where the ray is parallel to the plane or the point is behind
    the camera.
    """
    check_rig(rig)
    o, d = rig.camera.rays(cam_uv)
    n, off = column_planes(rig.projector, proj_u)
    denom = np.sum(n * d, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (off - np.sum(n * o, axis=-1)) / denom
    t = np.where((np.abs(denom) > 1e-12) & (t > 0), t, np.nan)
    return o + t[..., None] * d


def triangulate_rays(rig: Rig, cam_uv, proj_uv) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares (midpoint) intersection of camera and projector rays.

    Minimises ``|o1 + t1 d1 - (o2 + t2 d2)|^2`` over ``t1, t2`` and returns the midpoint.

    Parameters
    ----------
    rig : Rig
    cam_uv, proj_uv : (..., 2) pixel coordinates in the camera and the projector

    Returns
    -------
    points : (..., 3) world points (NaN for parallel rays or points behind either device)
    residual : (...) distance between the rays at closest approach (m)
    """
    check_rig(rig)
    o1, d1 = rig.camera.rays(cam_uv)
    o2, d2 = rig.projector.rays(proj_uv)
    w = o1 - o2
    b = np.sum(d1 * d2, axis=-1)
    dw1 = np.sum(d1 * w, axis=-1)
    dw2 = np.sum(d2 * w, axis=-1)
    denom = 1.0 - b * b  # unit directions
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (b * dw2 - dw1) / denom
        t2 = (dw2 - b * dw1) / denom
    ok = (denom > 1e-14) & (t1 > 0) & (t2 > 0)
    p1 = o1 + t1[..., None] * d1
    p2 = o2 + t2[..., None] * d2
    pts = np.where(ok[..., None], 0.5 * (p1 + p2), np.nan)
    res = np.where(ok, np.linalg.norm(p1 - p2, axis=-1), np.nan)
    return pts, res


def triangulate(rig: Rig, corr: Correspondences, *, method: str = "rays") -> PointCloud:
    """Point cloud from correspondences: ``"rays"`` (column and row) or ``"plane"`` (column only)."""
    if method == "rays":
        pts, res = triangulate_rays(rig, corr.cam_uv, corr.proj_uv)
    elif method == "plane":
        pts = triangulate_plane(rig, corr.cam_uv, corr.proj_uv[:, 0])
        res = np.zeros(len(corr))
    else:
        raise ValueError(f"unknown triangulation method {method!r}; valid: 'plane', 'rays'")
    keep = np.all(np.isfinite(pts), axis=-1)
    return PointCloud(pts[keep], corr.proj_uv[keep], res[keep])


def skew(v) -> np.ndarray:
    x, y, z = np.asarray(v, float)
    return np.array([[0, -z, y], [z, 0, -x], [-y, x, 0.0]])


def fundamental_matrix(rig: Rig) -> np.ndarray:
    """Fundamental matrix F with ``x_cam^T F x_proj = 0`` for homogeneous pixel coordinates.

    ``F @ (u_p, v_p, 1)`` is the camera epipolar line ``(a, b, c)`` of projector pixel
    ``(u_p, v_p)`` (``a u + b v + c = 0``), in this package's pixel convention.
    """
    check_rig(rig)
    Rp, Rc = rig.projector.pose.rotation, rig.camera.pose.rotation
    # projector device -> camera device: X_c = R X_p + t
    R = Rc.T @ Rp
    t = Rc.T @ (rig.projector.position - rig.camera.position)
    E = skew(t) @ R
    Kc, Kp = rig.camera.intrinsics.K, rig.projector.intrinsics.K
    return np.linalg.inv(Kc).T @ E @ np.linalg.inv(Kp)


def epipolar_distance(F: np.ndarray, cam_uv, proj_uv) -> np.ndarray:
    """Distance (camera pixels) from ``cam_uv`` to the epipolar line of ``proj_uv``; (...) float."""
    cam = np.asarray(cam_uv, float)
    proj = np.asarray(proj_uv, float)
    xp = np.concatenate([proj, np.ones((*proj.shape[:-1], 1))], axis=-1)
    line = xp @ F.T
    num = line[..., 0] * cam[..., 0] + line[..., 1] * cam[..., 1] + line[..., 2]
    return np.abs(num) / np.hypot(line[..., 0], line[..., 1])


def true_projector_uv(
    positions: np.ndarray, projector: Camera, lit: np.ndarray | None = None
) -> np.ndarray:
    """Continuous projector coordinates (u, v) of world points (e.g. the ground-truth
    positions seen through camera pixel centres): where each camera pixel's ray meets the
    projector image, pixel centres at ``(col + 0.5, row + 0.5)``.

    Parameters
    ----------
    positions : (rows, cols, 3) float
        World points (NaN where nothing was hit).
    projector : Camera
    lit : (rows, cols) bool, optional
        Points actually reached by projector light (see :func:`projector_visibility`); others
        get NaN.

    Returns
    -------
    (rows, cols, 2) float64, NaN where outside the projector or not lit
    """
    uv, z = projector.project(positions)
    W, H = projector.intrinsics.width, projector.intrinsics.height
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(uv).all(axis=-1) & (z > 0)
        ok &= (uv[..., 0] >= 0) & (uv[..., 0] < W) & (uv[..., 1] >= 0) & (uv[..., 1] < H)
    if lit is not None:
        ok &= np.asarray(lit, bool)
    return np.where(ok[..., None], uv, np.nan).astype(np.float64)


def true_correspondences(
    positions: np.ndarray, projector: Camera, lit: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Projector column and row of world points: :func:`true_projector_uv` floored.

    Returns
    -------
    col, row : (rows, cols) int64, -1 where outside the projector or not lit
    """
    uv = true_projector_uv(positions, projector, lit)
    ok = np.isfinite(uv[..., 0])
    col = np.where(ok, np.floor(np.where(ok, uv[..., 0], 0)), -1).astype(np.int64)
    row = np.where(ok, np.floor(np.where(ok, uv[..., 1], 0)), -1).astype(np.int64)
    return col, row


def projector_visibility(
    positions: np.ndarray,
    projector: Camera,
    guide_depth: np.ndarray,
    *,
    rel_tol: float = 0.01,
    window: int = 3,
) -> np.ndarray:
    """Which world points the projector lights directly (not in its cast shadow).

    The guide view has the projector's centre and intrinsics, so a point is lit if nothing in
    the guide view lies in front of it: its projector depth is at most the largest guide
    ground-truth depth over the ``window x window`` pixels around its projector pixel, plus
    ``rel_tol``. The window keeps surfaces lit at grazing incidence (whose depth changes a lot
    within one pixel) lit; a point in a cast shadow is behind the occluder over the whole window
    (except within ``window // 2`` pixels of the shadow's edge).

    Parameters
    ----------
    positions : (..., 3) world points
    projector : Camera
    guide_depth : (H, W) float64 ground-truth z-depth of the guide view (NaN = miss)

    Returns
    -------
    (...) bool
    """
    from scipy import ndimage

    guide_depth = np.asarray(guide_depth, float)
    if guide_depth.shape != projector.intrinsics.shape:
        raise ValueError(
            f"guide_depth {guide_depth.shape} must have the projector shape "
            f"{projector.intrinsics.shape}"
        )
    far = ndimage.maximum_filter(
        np.nan_to_num(guide_depth, nan=-np.inf), size=window, mode="nearest"
    )
    col, row = true_correspondences(positions, projector)
    _, z = projector.project(positions)
    ok = col >= 0
    gd = np.full(col.shape, np.nan)
    gd[ok] = far[row[ok], col[ok]]
    with np.errstate(invalid="ignore"):
        return ok & (z <= gd * (1 + rel_tol))


def depth_in_view(points: np.ndarray, view: Camera, *, reduce: str = "mean") -> np.ndarray:
    """Resample world points into a camera as a z-depth map with NaN holes.

    Parameters
    ----------
    points : (n, 3) world points
    view : Camera (e.g. the guide camera, whose pixels are projector pixels)
    reduce : "mean" or "min"
        How several points landing in one pixel combine ("min" keeps the front-most).

    Returns
    -------
    (rows, cols) float64 z-depth (m); NaN where no point landed.
    """
    if reduce not in ("mean", "min"):
        raise ValueError(f"unknown reduce {reduce!r}; valid: 'mean', 'min'")
    rows, cols = view.intrinsics.shape
    out = np.full(rows * cols, np.nan)
    pts = np.asarray(points, float).reshape(-1, 3)
    if len(pts) == 0:
        return out.reshape(rows, cols)
    uv, z = view.project(pts)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(uv).all(axis=-1) & (z > 0)
        ok &= (uv[:, 0] >= 0) & (uv[:, 0] < cols) & (uv[:, 1] >= 0) & (uv[:, 1] < rows)
    idx = np.floor(uv[ok, 1]).astype(np.int64) * cols + np.floor(uv[ok, 0]).astype(np.int64)
    z = z[ok]
    if reduce == "mean":
        s = np.bincount(idx, weights=z, minlength=rows * cols)
        n = np.bincount(idx, minlength=rows * cols)
        hit = n > 0
        out[hit] = s[hit] / n[hit]
    else:
        m = np.full(rows * cols, np.inf)
        np.minimum.at(m, idx, z)
        hit = np.isfinite(m)
        out[hit] = m[hit]
    return out.reshape(rows, cols)


def depth_at_proj_pixels(cloud: PointCloud, view: Camera, *, reduce: str = "mean") -> np.ndarray:
    """Depth map in the guide view indexed by each point's projector pixel (not its reprojection).

    The guide camera shares the projector's centre and intrinsics, so the projector pixel a
    point was measured through *is* its guide pixel; the depth stored is the point's z in the
    guide frame. This keeps a wrongly triangulated point at the pixel that was scanned.
    """
    rows, cols = view.intrinsics.shape
    out = np.full(rows * cols, np.nan)
    if len(cloud) == 0:
        return out.reshape(rows, cols)
    z = view.pose.world_to_device(cloud.points)[:, 2]
    c = np.floor(cloud.proj_uv[:, 0]).astype(np.int64)
    r = np.floor(cloud.proj_uv[:, 1]).astype(np.int64)
    ok = (c >= 0) & (c < cols) & (r >= 0) & (r < rows) & (z > 0)
    idx = r[ok] * cols + c[ok]
    z = z[ok]
    if reduce == "mean":
        s = np.bincount(idx, weights=z, minlength=rows * cols)
        n = np.bincount(idx, minlength=rows * cols)
        out[n > 0] = s[n > 0] / n[n > 0]
    elif reduce == "min":
        m = np.full(rows * cols, np.inf)
        np.minimum.at(m, idx, z)
        out[np.isfinite(m)] = m[np.isfinite(m)]
    else:
        raise ValueError(f"unknown reduce {reduce!r}; valid: 'mean', 'min'")
    return out.reshape(rows, cols)


__all__ = [
    "Correspondences",
    "PointCloud",
    "check_rig",
    "column_planes",
    "depth_at_proj_pixels",
    "depth_in_view",
    "epipolar_distance",
    "fundamental_matrix",
    "projector_visibility",
    "skew",
    "triangulate",
    "triangulate_plane",
    "triangulate_rays",
    "true_correspondences",
    "true_projector_uv",
]
