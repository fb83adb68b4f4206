"""Dot patterns, dot detection with sub-pixel centroids, ghost rejection and multiplexed scheduling.

A dot is one projector pixel (or a small disk of them). Several dots share one projected frame
when the camera cannot confuse them: their projector positions are at least
``min_proj_spacing`` pixels apart and the segments of the camera epipolar lines on which they
can appear (for the scene's depth range) stay at least ``min_cam_spacing`` camera pixels apart.
A blob is assigned to the one dot whose segment it lies on; blobs on no segment and dimmer blobs
on an already-claimed segment are interreflection ghosts and are rejected.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy import ndimage

from simlunar.geometry import Rig
from simlunar.scanner import _schedule as _sched
from simlunar.scanner.triangulate import check_rig


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
class DotSchedule:
    """Dots grouped into frames, with a lower bound on the number of frames.

    Attributes
    ----------
    frames : list of int arrays, indices into the dots; every dot appears exactly once
    colour : (n,) int, the frame of each dot
    clique : (k,) int, dots that conflict pairwise (so no schedule has fewer than k frames)
    """

    frames: list
    colour: np.ndarray
    clique: np.ndarray

    @property
    def lower_bound(self) -> int:
        """Size of the largest set of mutually conflicting dots found (<= optimal frames)."""
        return len(self.clique)

    @property
    def frames_over_bound(self) -> float:
        return len(self.frames) / max(self.lower_bound, 1)


def _epipole(rig: Rig) -> tuple[np.ndarray, float]:
    """Homogeneous camera image (x, y, w) of the projector centre (the camera epipole)."""
    X, Y, Z = rig.camera.pose.world_to_device(rig.projector.position)
    K = rig.camera.intrinsics
    return np.array([K.fx * X + K.cx * Z, K.fy * Y + K.cy * Z]), float(Z)


def _epipolar_coordinates(rig: Rig, seg: np.ndarray, sep: float):
    """Band coordinate, intervals along the epipolar lines and the band geometry.

    Returns ``(w, s0, s1, reach, clique_width, cyclic, period)``: every two segments closer than
    ``sep`` have ``|w_i - w_j| < reach`` (cyclically with ``period`` when ``cyclic``) and
    intervals ``[s0, s1]`` less than ``sep`` apart; points at a common ``s <= s_top`` of
    segments whose ``w`` differ by less than ``clique_width(s_top, d)`` are less than ``d``
    apart.
    """
    exy, ez = _epipole(rig)
    scale = float(np.abs(seg).max()) + 1.0
    far = abs(ez) * 1e7 * scale < float(np.hypot(*exy)) or abs(ez) < 1e-300
    if far:
        # epipole at infinity (or as good as): parallel lines, offset and position along them
        d = exy / np.hypot(*exy)
        nrm = np.array([-d[1], d[0]])
        wend = seg @ nrm
        w = wend.mean(axis=1)
        spread = float(np.abs(wend - w[:, None]).max())
        s = seg @ d
        s0, s1 = s.min(axis=1), s.max(axis=1)
        reach = sep + 2 * spread

        def clique_width(s_top, sep_eff):
            return sep_eff - 2 * spread

        return w, s0, s1, reach * (1 + 1e-9), clique_width, False, 0.0
    e = exy / ez
    rel = seg - e
    r = np.hypot(rel[..., 0], rel[..., 1])
    # distance from the epipole to each segment (its nearest point) and to its far end
    s0 = _dist_to_segments(e, seg)
    s1 = r.max(axis=1)
    th = np.arctan2(rel[..., 1], rel[..., 0])
    mid = rel.mean(axis=1)
    w = np.arctan2(mid[:, 1], mid[:, 0])
    dth = np.abs(np.angle(np.exp(1j * (th - w[:, None]))))
    spread = float(dth.max())
    s_min = float(s0.min())
    reach = (np.arcsin(sep / s_min) if sep < s_min else np.pi) + 2 * spread

    def clique_width(s_top, sep_eff):
        # chord between points at distance s <= s_top on lines dw apart: <= s_top * dw
        return sep_eff / s_top - 2 * spread

    # cut the circle of angles in its widest empty gap
    ws = np.sort(w)
    gaps = np.diff(np.r_[ws, ws[0] + 2 * np.pi])
    g = int(np.argmax(gaps))
    cut = ws[(g + 1) % len(ws)]
    w = np.mod(w - cut, 2 * np.pi)
    cyclic = bool(gaps[g] <= reach)
    return w, s0, s1, reach * (1 + 1e-9), clique_width, cyclic, 2 * np.pi


def _dist_to_segments(p: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Distances from one point (2,) to segments (n, 2, 2)."""
    return point_segment_distance(np.asarray(p, float)[None], seg)[0]


def _largest_clique(w, s0, s1, puv, clique_width, sep, min_proj_spacing, q=4, slab=None):
    """Largest set of pairwise conflicting dots among two kinds of windows.

    Camera: the line positions are cut into slabs (``slab`` long, default 8 ``sep``). In each,
    for a few margins m, dots whose intervals widened by m share a point s* of the slab, and
    whose band coordinates lie in ``q`` consecutive bins of width
    ``clique_width(slab end + m, sqrt(sep^2 - 4 m^2)) / q``: each has a point within m of
    distance s* from the epipole, and two such points are less than
    ``sqrt((2 m)^2 + sep^2 - 4 m^2) = sep`` apart. Projector: dots in a square of ``q`` x ``q``
    bins of side ``min_proj_spacing / (q sqrt 2)`` (pairwise closer than the spacing).
    """
    best = np.empty(0, np.int64)
    slab = 8.0 * sep if slab is None else slab
    lo, hi = float(s0.min()), float(s1.max())
    n_slab = max(int(np.ceil((hi - lo) / slab)), 1)
    # m = 0: the widest band; m -> sep / 2: collinear segments whose intervals are < sep apart
    for m in (0.0, 0.25 * sep, 0.5 * sep * (1 - 1e-6)):
        sep_eff = np.sqrt(sep * sep - 4 * m * m)
        for k in range(n_slab):
            a, e = lo + k * slab, lo + (k + 1) * slab
            width = clique_width(e + m, sep_eff) / q * (1 - 1e-9)
            if width <= 0:
                continue
            sel = np.flatnonzero((s0 - m < e) & (s1 + m >= a))
            if len(sel) <= len(best):
                continue
            c0 = np.maximum(s0[sel] - m, a)
            c1 = np.minimum(s1[sel] + m, np.nextafter(e, -np.inf))
            b = np.floor((w[sel] - w[sel].min()) / width).astype(np.int64)
            order = np.argsort(b, kind="stable")
            depth, b0, s_star = _sched.max_overlap_windows(b[order], order, c0, c1, q)
            if depth > len(best):
                inwin = (b >= b0) & (b < b0 + q) & (c0 <= s_star) & (c1 >= s_star)
                best = sel[inwin]
    if min_proj_spacing > 0:
        side = min_proj_spacing / (q * np.sqrt(2)) * (1 - 1e-9)
        ij = np.floor((puv - puv.min(axis=0)) / side).astype(np.int64)
        nx = int(ij[:, 0].max()) + q + 1
        if nx * (int(ij[:, 1].max()) + q + 1) < 2**62:
            # every q x q window of bins that holds a dot, keyed by its lower corner
            dy, dx = np.divmod(np.arange(q * q), q)
            key = (ij[:, 1, None] - dy + q) * nx + (ij[:, 0, None] - dx + q)
            keys, counts = np.unique(key.ravel(), return_counts=True)
            k = int(np.argmax(counts))
            if counts[k] > len(best):
                y0, x0 = divmod(int(keys[k]), nx)
                x0, y0 = x0 - q, y0 - q
                inwin = (ij[:, 0] >= x0) & (ij[:, 0] < x0 + q)
                inwin &= (ij[:, 1] >= y0) & (ij[:, 1] < y0 + q)
                best = np.flatnonzero(inwin)
    return best


def check_spacings(min_cam_spacing: float, min_proj_spacing: float) -> None:
    """Raise ValueError unless both scheduling spacings are > 0 px (finite)."""
    sep, psp = float(min_cam_spacing), float(min_proj_spacing)
    if not (0 < sep < float("inf") and 0 < psp < float("inf")):
        raise ValueError(
            f"min_cam_spacing and min_proj_spacing must be > 0 px, got {sep} and {psp}"
        )


def dot_schedule(
    rig: Rig,
    proj_uv,
    *,
    depth_range: tuple[float, float],
    min_proj_spacing: float = 8.0,
    min_cam_spacing: float = 6.0,
    bound: bool = True,
) -> DotSchedule:
    """Group dots into frames along the epipolar structure, with a lower bound on frames.

    Two dots conflict (must not share a frame) if they are closer than ``min_proj_spacing``
    projector pixels or their camera epipolar segments (:func:`epipolar_segments` for
    ``depth_range``) come closer than ``min_cam_spacing`` camera pixels (exact segment distance,
    :func:`segment_distance`). All segments lie on lines through the camera epipole (the image
    of the projector centre); each dot gets a band coordinate (the angle of its line about the
    epipole, or its offset when the epipole is at infinity) and an interval along the line
    (distance from the epipole). Dots are swept by the start of their interval, all bands at
    once, and coloured first-fit: each takes the lowest frame not used by an already scheduled
    dot it conflicts with. For the dots of one epipolar line this is the greedy colouring of an
    interval graph by left end, which is optimal (frames = deepest overlap); conflicts with
    dots of the neighbouring lines and bands and in the projector are checked exactly. Candidates come from the band
    index (conflicting dots are at most two bands apart) and a binary search on interval
    starts, so the work is the number of dots times the number of scheduled dots within reach
    of one segment; no conflict graph or pair list is built.

    The lower bound is the largest set of mutually conflicting dots found: in slabs of the line
    position, dots whose lines are so close that points at a common distance from the epipole
    are less than ``min_cam_spacing`` apart and whose intervals share such a distance; or dots
    in a projector square of diagonal ``min_proj_spacing``. No schedule has fewer frames.

    Parameters
    ----------
    rig : Rig
    proj_uv : (n, 2) projector pixel coordinates of the dots
    depth_range : (near, far) projector z-depth bounds of the scene (m)
    min_proj_spacing, min_cam_spacing : float
        Projector pixels, camera pixels (> 0).
    bound : bool
        Search the lower bound (on a second thread while colouring). False skips it (the
        frames are the same): ``clique`` is then empty and ``lower_bound`` 0.

    Returns
    -------
    DotSchedule
    """
    proj_uv = _as_uv(proj_uv, "dot positions")
    check_spacings(min_cam_spacing, min_proj_spacing)
    sep = float(min_cam_spacing)
    psp = float(min_proj_spacing)
    seg = np.ascontiguousarray(epipolar_segments(rig, proj_uv, depth_range))
    w, s0, s1, reach, clique_width, cyclic, period = _epipolar_coordinates(rig, seg, sep)
    # bands half as wide as the reach: conflicting dots are at most 2 bands apart
    reach_bands = 2
    bw = max(reach / reach_bands, float(np.ptp(w)) / 65536)  # at most ~65k bands
    reach_bands = int(np.ceil(reach / bw))
    if cyclic:
        nb = max(int(np.floor(period / bw)), 1)
        bw = period / nb
        reach_bands = int(np.ceil(reach / bw))
        band = np.minimum(np.floor(w / bw).astype(np.int64), nb - 1)
    else:
        band = np.floor((w - w.min()) / bw).astype(np.int64)
        nb = int(band.max()) + 1
    by_band = np.lexsort((s0, band))
    band_start = np.searchsorted(band[by_band], np.arange(nb + 1)).astype(np.int64)
    band_s0 = np.ascontiguousarray(s0[by_band])
    max_len = float(np.max(s1 - s0))
    # projector grid, cells one spacing wide
    pmin = proj_uv.min(axis=0)
    pcs = max(psp, float(np.ptp(proj_uv, axis=0).max()) / 4096)  # at most 4096^2 cells
    pij = np.floor((proj_uv - pmin) / pcs).astype(np.int64)
    pnx, pny = int(pij[:, 0].max()) + 1, int(pij[:, 1].max()) + 1
    pcell = pij[:, 1] * pnx + pij[:, 0]
    pidx = np.argsort(pcell, kind="stable")
    pstart = np.searchsorted(pcell[pidx], np.arange(pnx * pny + 1)).astype(np.int64)
    # sweep: all bands at once by interval start
    seq = np.lexsort((band, s0))
    args = (
        band,
        band_start,
        band_s0,
        by_band.astype(np.int64),
        s0,
        s1,
        seg,
        sep,
        reach_bands,
        cyclic,
        max_len,
        np.ascontiguousarray(proj_uv),
        pstart,
        pidx.astype(np.int64),
        pcell,
        pnx,
        pny,
        psp,
    )
    if not bound:
        colour = _sched.greedy_colour(seq.astype(np.int64), *args)
        clique = np.empty(0, np.int64)
        return DotSchedule(frames=_frames_from_colour(colour), colour=colour, clique=clique)
    # the lower bound is independent of the colouring: search it on a second core meanwhile
    # (both kernels release the GIL)
    with ThreadPoolExecutor(max_workers=1) as pool:
        bound = pool.submit(_largest_clique, w, s0, s1, proj_uv, clique_width, sep, psp)
        colour = _sched.greedy_colour(seq.astype(np.int64), *args)
        clique = bound.result()
    return DotSchedule(frames=_frames_from_colour(colour), colour=colour, clique=clique)


def _frames_from_colour(colour: np.ndarray) -> list[np.ndarray]:
    idx = np.argsort(colour, kind="stable")
    bounds = np.searchsorted(colour[idx], np.arange(int(colour.max()) + 2))
    return [idx[bounds[c] : bounds[c + 1]] for c in range(len(bounds) - 1)]


def schedule_dots(
    rig: Rig,
    proj_uv,
    *,
    depth_range: tuple[float, float],
    min_proj_spacing: float = 8.0,
    min_cam_spacing: float = 6.0,
    exact: bool = False,
) -> list[np.ndarray]:
    """Group dots into frames that the camera can decode without confusion.

    The frames of :func:`dot_schedule` (two dots share a frame only if they are at least
    ``min_proj_spacing`` projector pixels apart and their camera epipolar segments for
    ``depth_range`` stay at least ``min_cam_spacing`` camera pixels apart).

    Parameters
    ----------
    rig : Rig
    proj_uv : (n, 2) projector pixel coordinates of the dots
    depth_range : (near, far) projector z-depth bounds of the scene (m)
    min_proj_spacing, min_cam_spacing : float
    exact : bool
        One dot per frame (the reference mode that multiplexing is checked against).

    Returns
    -------
    list of int arrays, indices into ``proj_uv``; every dot appears exactly once
    """
    proj_uv = _as_uv(proj_uv, "dot positions")
    if exact:
        return [np.array([i]) for i in range(len(proj_uv))]
    return dot_schedule(
        rig,
        proj_uv,
        depth_range=depth_range,
        min_proj_spacing=min_proj_spacing,
        min_cam_spacing=min_cam_spacing,
        bound=False,  # the scan needs the frames only
    ).frames


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
