"""Dot patterns, dot detection with sub-pixel centroids, ghost rejection and multiplexed scheduling.

A dot is one projector pixel (or a small disk of them). Several dots share one projected frame
when the camera cannot confuse them: their projector positions are at least
``min_proj_spacing`` pixels apart and the segments of the camera epipolar lines on which they
can appear (for the scene's depth range) stay at least ``min_cam_spacing`` camera pixels apart.
A blob is assigned to the one dot whose segment it lies on; blobs on no segment and dimmer blobs
on an already-claimed segment are interreflection ghosts and are rejected.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy import ndimage

from simlunar.geometry import Rig
from simlunar.scanner.triangulate import check_rig

__all__ = [
    "Detections",
    "DotMatches",
    "detect_dots",
    "dot_pattern",
    "epipolar_segments",
    "match_dots",
    "point_segment_distance",
    "segment_distance",
]


def _as_uv(uv, name: str) -> np.ndarray:
    a = np.asarray(uv, dtype=float)
    if a.ndim != 2 or a.shape[1] != 2:
        raise ValueError(
            f"{name} must be an (n, 2) array of (u, v) pixel coordinates, got {a.shape}"
        )
    if len(a) == 0:
        raise ValueError(f"{name} is empty: at least one dot is needed")
    return a


def dot_pattern(shape: tuple[int, int], uv, *, radius: float = 0.0) -> np.ndarray:
    """Projector frame with dots lit.

    Parameters
    ----------
    shape : (H, W) projector pattern shape
    uv : (n, 2) dot centres in projector pixel coordinates
    radius : float
        0 lights the single pixel containing each centre; > 0 lights every pixel whose centre
        lies within ``radius`` pixels of it (a small disk).

    Returns
    -------
    (H, W) float32 in {0, 1}
    """
    uv = _as_uv(uv, "dot positions")
    H, W = shape
    if np.any((uv[:, 0] < 0) | (uv[:, 0] >= W) | (uv[:, 1] < 0) | (uv[:, 1] >= H)):
        raise ValueError(f"dot positions must lie inside the {W}x{H} projector")
    out = np.zeros((H, W), np.float32)
    if radius <= 0:
        out[np.floor(uv[:, 1]).astype(int), np.floor(uv[:, 0]).astype(int)] = 1.0
        return out
    r = int(np.ceil(radius))
    dv, du = np.mgrid[-r : r + 1, -r : r + 1]
    for u, v in uv:
        cc = np.floor(u).astype(int) + du
        rr = np.floor(v).astype(int) + dv
        inside = (np.hypot(cc + 0.5 - u, rr + 0.5 - v) <= radius) & (cc >= 0) & (cc < W)
        inside &= (rr >= 0) & (rr < H)
        out[rr[inside], cc[inside]] = 1.0
    return out


@dataclass(frozen=True, eq=False)
class Detections:
    """Bright blobs found in one camera frame.

    Attributes
    ----------
    uv : (m, 2) float64 sub-pixel centroids (u, v) in camera pixel coordinates
    flux : (m,) float64 summed background-subtracted intensity
    peak : (m,) float64 brightest pixel minus background
    """

    uv: np.ndarray
    flux: np.ndarray
    peak: np.ndarray

    def __len__(self) -> int:
        return self.uv.shape[0]


def detect_dots(
    image: np.ndarray,
    *,
    background=None,
    rel_threshold: float = 0.2,
    abs_threshold: float = 0.0,
    grow: int = 2,
    reject_border: bool = True,
) -> Detections:
    """Detect blobs and their intensity-weighted sub-pixel centroids.

    Pixels brighter than ``background + max(abs_threshold, rel_threshold * peak)`` (``peak`` = the
    brightest pixel above background) form 8-connected blobs; each blob's centroid is the
    intensity-weighted mean of pixel centres over the blob dilated by ``grow`` pixels, with
    weights ``max(image - background, 0)`` so the faint wings of a blurred spot count too.

    Parameters
    ----------
    image : (rows, cols) float
    background : float or (rows, cols) array, optional
        Image without the dots (e.g. the black frame); default the image median.
    rel_threshold, abs_threshold : float
    grow : int
    reject_border : bool
        Drop blobs whose grown region touches the image border (truncated spots).

    Returns
    -------
    Detections
    """
    img = np.asarray(image)
    if img.ndim != 2:
        raise ValueError(f"image must be 2-D (rows, cols), got {img.shape}")
    bg = np.median(img) if background is None else np.asarray(background)
    sig = np.subtract(img, bg, dtype=np.float64)
    np.maximum(sig, 0.0, out=sig)
    peak = float(sig.max()) if sig.size else 0.0
    thr = max(abs_threshold, rel_threshold * peak)
    empty = Detections(np.empty((0, 2)), np.empty(0), np.empty(0))
    if peak <= 0 or peak <= abs_threshold:
        return empty
    labels, n = ndimage.label(sig > thr, structure=np.ones((3, 3), bool))
    if n == 0:
        return empty
    rr, cc = np.nonzero(labels)
    # compiled: grow the blobs by ``grow`` px (each pixel to the nearest blob pixel's label)
    # and sum flux, moments and peak over the grown blobs, touching only pixels near blobs
    flux, su, sv, pk, edge = _blob_moments(
        labels, sig, rr.astype(np.int64), cc.astype(np.int64), int(max(grow, 0)), n
    )
    with np.errstate(invalid="ignore", divide="ignore"):
        u = su / flux
        v = sv / flux
    ok = flux > 0
    if reject_border:
        # a spot cut by the image border has a biased centroid
        ok &= ~edge
    return Detections(np.stack([u, v], axis=-1)[ok], flux[ok], pk[ok])


@njit(cache=True, nogil=True)
def _blob_moments(labels, sig, rr, cc, grow, n):  # pragma: no cover - compiled
    rows, cols = labels.shape
    g2 = grow * grow
    # pixels within ``grow`` of a blob pixel: nearest blob pixel's label (first found on ties)
    best = {}
    for i in range(rr.size):
        r, c = rr[i], cc[i]
        lab = labels[r, c]
        for dr in range(-grow, grow + 1):
            for dc in range(-grow, grow + 1):
                d2 = dr * dr + dc * dc
                if d2 > g2:
                    continue
                q_r, q_c = r + dr, c + dc
                if q_r < 0 or q_r >= rows or q_c < 0 or q_c >= cols:
                    continue
                key = q_r * cols + q_c
                if key in best:
                    old_d2, _ = best[key]
                    if d2 >= old_d2:
                        continue
                best[key] = (d2, lab)
    flux = np.zeros(n)
    su = np.zeros(n)
    sv = np.zeros(n)
    pk = np.zeros(n)
    edge = np.zeros(n, np.bool_)
    for key, val in best.items():
        k = val[1] - 1
        q_r, q_c = key // cols, key % cols
        s = sig[q_r, q_c]
        flux[k] += s
        su[k] += s * (q_c + 0.5)
        sv[k] += s * (q_r + 0.5)
        if s > pk[k]:
            pk[k] = s
        if q_r == 0 or q_r == rows - 1 or q_c == 0 or q_c == cols - 1:
            edge[k] = True
    return flux, su, sv, pk, edge


def epipolar_segments(rig: Rig, proj_uv, depth_range: tuple[float, float]) -> np.ndarray:
    """Camera-image segments on which projector dots can appear.

    Parameters
    ----------
    rig : Rig
    proj_uv : (n, 2) projector pixel coordinates
    depth_range : (z_near, z_far) projector z-depths (m) bounding the scene

    Returns
    -------
    (n, 2, 2) float64: for each dot the camera (u, v) of its near and far ends
    """
    check_rig(rig)
    proj_uv = _as_uv(proj_uv, "dot positions")
    z0, z1 = float(depth_range[0]), float(depth_range[1])
    if not 0 < z0 < z1:
        raise ValueError(f"depth_range must be 0 < near < far (m), got {depth_range}")
    d = rig.projector.directions_device(proj_uv)
    ends = []
    for z in (z0, z1):
        pw = rig.projector.pose.device_to_world(d * z)
        uv, zc = rig.camera.project(pw)
        if np.any(zc <= 0):
            raise ValueError(
                "the camera does not see the projected area: projected points lie "
                "behind the triangulation camera"
            )
        ends.append(uv)
    return np.stack(ends, axis=1)


def point_segment_distance(p: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Distances between points (m, 2) and segments (k, 2, 2): (m, k)."""
    a = seg[None, :, 0]
    ab = seg[None, :, 1] - a
    ap = p[:, None] - a
    L2 = np.sum(ab * ab, axis=-1)
    t = np.clip(np.sum(ap * ab, axis=-1) / np.where(L2 > 0, L2, 1.0), 0.0, 1.0)
    return np.linalg.norm(ap - t[..., None] * ab, axis=-1)


def segment_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Exact distances between 2-D segments ``a`` (..., 2, 2) and ``b`` (..., 2, 2) (broadcast).

    Zero where the segments cross or touch, else the least of the four endpoint-to-segment
    distances. This is the camera test of :func:`dot_schedule`.
    """
    a = np.asarray(a, float)
    b = np.asarray(b, float)

    def pseg(p, s):
        ab = s[..., 1, :] - s[..., 0, :]
        ap = p - s[..., 0, :]
        L2 = np.sum(ab * ab, axis=-1)
        t = np.clip(np.sum(ap * ab, axis=-1) / np.where(L2 > 0, L2, 1.0), 0.0, 1.0)
        return np.linalg.norm(ap - t[..., None] * ab, axis=-1)

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (
            r[..., 0] - p[..., 0]
        )

    a0, a1, b0, b1 = a[..., 0, :], a[..., 1, :], b[..., 0, :], b[..., 1, :]
    cross = (orient(a0, a1, b0) * orient(a0, a1, b1) < 0) & (
        orient(b0, b1, a0) * orient(b0, b1, a1) < 0
    )
    d = np.minimum(np.minimum(pseg(a0, b), pseg(a1, b)), np.minimum(pseg(b0, a), pseg(b1, a)))
    return np.where(cross, 0.0, d)


@dataclass(frozen=True, eq=False)
class DotMatches:
    """Dots found in one frame.

    Attributes
    ----------
    dot : (m,) int indices (into the frame's dot list) of the dots found
    cam_uv : (m, 2) camera centroids of those dots
    n_ghosts : int blobs rejected (off every segment, or dimmer duplicates on a claimed one)
    """

    dot: np.ndarray
    cam_uv: np.ndarray
    n_ghosts: int


def match_dots(det: Detections, segments: np.ndarray, *, tol: float = 2.0) -> DotMatches:
    """Assign detected blobs to scheduled dots through their epipolar segments.

    A blob within ``tol`` camera pixels of exactly one segment belongs to that dot; of several
    blobs on one segment the one with the largest flux is kept (an interreflection ghost is
    dimmer than the directly lit spot). Blobs near no segment or near several are rejected.

    Parameters
    ----------
    det : Detections
    segments : (k, 2, 2) camera segments of the frame's dots (:func:`epipolar_segments`)
    tol : float camera pixels
    """
    if len(det) == 0:
        return DotMatches(np.empty(0, np.int64), np.empty((0, 2)), 0)
    d = point_segment_distance(det.uv, segments)
    near = d <= tol
    single = near.sum(axis=1) == 1
    cand = np.where(single, np.argmax(near, axis=1), -1)
    dots, uvs = [], []
    for k in np.unique(cand[cand >= 0]):
        blobs = np.flatnonzero(cand == k)
        best = blobs[np.argmax(det.flux[blobs])]
        dots.append(int(k))
        uvs.append(det.uv[best])
    n_found = len(dots)
    return DotMatches(
        np.asarray(dots, np.int64), np.asarray(uvs, float).reshape(-1, 2), len(det) - n_found
    )
