"""Dot scheduling: which dots may share a frame. Dots conflict when their epipolar segments (the
camera-image lines their light can land on over the scene's depth range) come closer than the
camera spacing, or the dots themselves closer than the projector spacing; frames are colours of
that conflict graph (greedy in epipolar order, optimal for the interval graphs of one band)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Rig
from simlunar.scanner import _schedule as _sched
from simlunar.scanner.dots import _as_uv, epipolar_segments, point_segment_distance

__all__ = ["DotSchedule", "check_spacings", "dot_schedule", "schedule_dots"]


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


def _largest_clique(w, s0, s1, puv, clique_width, sep, min_proj_spacing):
    """Largest set of pairwise conflicting dots among two kinds of windows: the larger of
    :func:`_camera_clique` and (for ``min_proj_spacing > 0``) :func:`_projector_clique`."""
    best = _camera_clique(w, s0, s1, clique_width, sep)
    if min_proj_spacing > 0:
        proj = _projector_clique(puv, min_proj_spacing)
        if proj is not None and len(proj) > len(best):
            best = proj
    return best


def _camera_clique(w, s0, s1, clique_width, sep, q=4, slab=None):
    """Largest set of dots whose camera segments conflict pairwise, found in windows.

    The line positions are cut into slabs (``slab`` long, default 8 ``sep``). In each, for a
    few margins m, dots whose intervals widened by m share a point s* of the slab, and whose
    band coordinates lie in ``q`` consecutive bins of width
    ``clique_width(slab end + m, sqrt(sep^2 - 4 m^2)) / q``: each has a point within m of
    distance s* from the epipole, and two such points are less than
    ``sqrt((2 m)^2 + sep^2 - 4 m^2) = sep`` apart.
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
    return best


def _projector_clique(puv, min_proj_spacing, q=4):
    """Most dots in one square of ``q`` x ``q`` bins of side ``min_proj_spacing / (q sqrt 2)``
    (pairwise closer than the spacing), or None where the bin grid is too large to key."""
    side = min_proj_spacing / (q * np.sqrt(2)) * (1 - 1e-9)
    ij = np.floor((puv - puv.min(axis=0)) / side).astype(np.int64)
    nx = int(ij[:, 0].max()) + q + 1
    if nx * (int(ij[:, 1].max()) + q + 1) >= 2**62:
        return None
    # every q x q window of bins that holds a dot, keyed by its lower corner
    dy, dx = np.divmod(np.arange(q * q), q)
    key = (ij[:, 1, None] - dy + q) * nx + (ij[:, 0, None] - dx + q)
    keys, counts = np.unique(key.ravel(), return_counts=True)
    y0, x0 = divmod(int(keys[int(np.argmax(counts))]), nx)
    x0, y0 = x0 - q, y0 - q
    inwin = (ij[:, 0] >= x0) & (ij[:, 0] < x0 + q)
    inwin &= (ij[:, 1] >= y0) & (ij[:, 1] < y0 + q)
    return np.flatnonzero(inwin)


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
    bands, reach_bands = _band_index(w, s0, reach, cyclic, period)
    max_len = float(np.max(s1 - s0))
    puv = np.ascontiguousarray(proj_uv)
    cells = _projector_cells(proj_uv, psp)
    # sweep: all bands at once by interval start
    seq = np.lexsort((bands[0], s0)).astype(np.int64)
    args = (seq, *bands, s0, s1, seg, sep, reach_bands, cyclic, max_len, puv, *cells, psp)
    if not bound:
        colour = _sched.greedy_colour(*args)
        clique = np.empty(0, np.int64)
        return DotSchedule(frames=_frames_from_colour(colour), colour=colour, clique=clique)
    # the lower bound is independent of the colouring: search it on a second core meanwhile
    # (both kernels release the GIL)
    with ThreadPoolExecutor(max_workers=1) as pool:
        search = pool.submit(_largest_clique, w, s0, s1, proj_uv, clique_width, sep, psp)
        colour = _sched.greedy_colour(*args)
        clique = search.result()
    return DotSchedule(frames=_frames_from_colour(colour), colour=colour, clique=clique)


def _band_index(w, s0, reach: float, cyclic: bool, period: float):
    """Dots binned into bands of the band coordinate ``w``, half as wide as the reach (so
    conflicting dots are at most 2 bands apart; at most ~65k bands).

    Returns ``((band, band_start, band_s0, band_idx), reach_bands)``: each dot's band, where
    each band starts in the band order, the interval starts and the dot indices in that order
    (by band, then start), and the bands a conflict can reach.
    """
    reach_bands = 2
    bw = max(reach / reach_bands, float(np.ptp(w)) / 65536)
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
    return (band, band_start, band_s0, by_band.astype(np.int64)), reach_bands


def _projector_cells(proj_uv, psp: float):
    """The dots in a projector grid of cells one spacing wide (at most 4096^2 cells).

    Returns ``(cell_start, cell_idx, cell_of, nx, ny)``: where each cell starts in the cell
    order, the dot indices in that order, each dot's cell and the grid size.
    """
    pmin = proj_uv.min(axis=0)
    pcs = max(psp, float(np.ptp(proj_uv, axis=0).max()) / 4096)
    pij = np.floor((proj_uv - pmin) / pcs).astype(np.int64)
    pnx, pny = int(pij[:, 0].max()) + 1, int(pij[:, 1].max()) + 1
    pcell = pij[:, 1] * pnx + pij[:, 0]
    pidx = np.argsort(pcell, kind="stable")
    pstart = np.searchsorted(pcell[pidx], np.arange(pnx * pny + 1)).astype(np.int64)
    return pstart, pidx.astype(np.int64), pcell, pnx, pny


def _frames_from_colour(colour: np.ndarray) -> list[np.ndarray]:
    idx = np.argsort(colour, kind="stable")
    bounds = np.searchsorted(colour[idx], np.arange(int(colour.max()) + 2))
    return [idx[bounds[c] : bounds[c + 1]] for c in range(len(bounds) - 1)]


def schedule_dots(
    rig: Rig,
    proj_uv,
    *,
    exact: bool = False,
    depth_range: tuple[float, float],
    min_proj_spacing: float = 8.0,
    min_cam_spacing: float = 6.0,
) -> list[np.ndarray]:
    """Group dots into frames that the camera can decode without confusion.

    The frames of :func:`dot_schedule` (two dots share a frame only if they are at least
    ``min_proj_spacing`` projector pixels apart and their camera epipolar segments for
    ``depth_range`` stay at least ``min_cam_spacing`` camera pixels apart), without its
    lower bound; or, with ``exact``, one dot per frame (the reference mode that multiplexing
    is checked against).

    Parameters
    ----------
    exact : bool
        One dot per frame instead of the multiplexed frames.
    rig, proj_uv, depth_range, min_proj_spacing, min_cam_spacing
        As for :func:`dot_schedule`.

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
