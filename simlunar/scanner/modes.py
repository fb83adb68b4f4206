"""Scan modes: full gray code, ambiguity enhancement (gray code + planned dot rescans), data reduction.

The modes are NumPy-only and drive any *capture* object with two methods:

``capture.render(patterns) -> (n, rows, cols) float``
    Noise-free camera images of the scene under ``n`` projector patterns (projector shape
    (H, W), values in [0, 1]). Each pattern counts as one render.
``capture.sense(images) -> (n, rows, cols) float``
    Captured frames: sensor noise, quantisation and response applied per frame.

:mod:`simlunar.study.scanner` provides the Mitsuba-backed capture; tests use NumPy ones.
Inverse patterns come from linearity of light transport (``bits + 2`` renders instead of
``2 * bits + 2``) unless ``inverses="render"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simlunar.geometry import Rig
from simlunar.scanner import dots as _dots
from simlunar.scanner import gray_code as gc
from simlunar.scanner.triangulate import (
    Correspondences,
    PointCloud,
    check_rig,
    depth_at_proj_pixels,
    triangulate,
)


@dataclass(frozen=True, eq=False)
class GrayScan:
    """Result of a full gray-code scan.

    Attributes
    ----------
    decode : GrayDecode (camera view)
    cloud : PointCloud of every valid camera pixel
    depth : (H, W) float64 z-depth in the guide (projector) view, NaN holes
    renders : int number of rendered frames
    frames : dict of the captured 'white' and 'black' frames and, with ``keep_frames``, the
        'images' (OpenCV-ordered stack)
    """

    decode: gc.GrayDecode
    cloud: PointCloud
    depth: np.ndarray
    renders: int
    frames: dict = field(repr=False)


@dataclass(frozen=True, eq=False)
class DotScan:
    """Result of scanning a set of dots.

    Attributes
    ----------
    proj_uv : (n, 2) projector coordinates of the dots asked for
    found : (n,) bool dots detected and triangulated
    cam_uv : (n, 2) camera centroids (NaN where not found)
    cloud : PointCloud of the found dots
    depth : (H, W) guide-view depth with only the found dots' pixels set (NaN elsewhere)
    renders : int frames rendered (dot frames + one black frame)
    frames_per_dot : list of index arrays (the schedule)
    n_ghosts : int blobs rejected as interreflection ghosts or ambiguities
    """

    proj_uv: np.ndarray
    found: np.ndarray
    cam_uv: np.ndarray
    cloud: PointCloud
    depth: np.ndarray
    renders: int
    frames_per_dot: list
    n_ghosts: int


def _check_patterns(capture, patterns: np.ndarray) -> np.ndarray:
    imgs = np.asarray(capture.render(patterns))
    if imgs.ndim != 3 or imgs.shape[0] != len(patterns):
        raise ValueError(f"capture.render returned shape {imgs.shape} for {len(patterns)} patterns")
    if imgs.dtype not in (np.float32, np.float64):
        imgs = imgs.astype(np.float64)
    return imgs


def gray_code_scan(
    capture,
    rig: Rig,
    *,
    black_threshold: float = 0.05,
    white_threshold: float = 0.01,
    inverses: str = "linearity",
    method: str = "plane",
    require_reliable: bool = True,
    subpixel: bool = False,
    keep_frames: bool = False,
) -> GrayScan:
    """Full gray-code scan (columns and rows) decoded and triangulated.

    Frames are streamed into a :class:`~simlunar.scanner.gray_code.GrayDecoder` as they are
    captured: white and black are rendered first, then each bit's pattern (and its inverse,
    by linearity or rendered) is rendered, sensed and decoded before the next, so memory
    holds a few frames plus the per-pixel bits, never the whole stack. Frames are sensed in
    OpenCV stack order (pattern, inverse pairs, then white and black).

    Parameters
    ----------
    capture : object with ``render`` and ``sense`` (module docstring)
    rig : Rig
    black_threshold, white_threshold : float
        OpenCV's validity and bit-reliability thresholds in captured-frame units ([0, 1]).
    inverses : "linearity" or "render"
        Obtain inverse-pattern images from white, black and pattern renders, or render them.
    method : "plane" (camera ray x projector column plane) or "rays" (column and row rays)
    require_reliable : bool
        A pixel with any unreliable bit is invalid (OpenCV's behaviour).
    subpixel : bool
        Sub-pixel stripe-edge refinement of the decoded columns and rows
        (:func:`simlunar.scanner.gray_code.refine_subpixel`) instead of projector pixel centres.
    keep_frames : bool
        Keep the captured stack in ``GrayScan.frames["images"]`` (as captured, float32 for
        :class:`~simlunar.study.scanner.RenderCapture`); white and black are always kept.

    Returns
    -------
    GrayScan
    """
    check_rig(rig)
    if inverses not in ("linearity", "render"):
        raise ValueError(f"unknown inverses option {inverses!r}; valid: 'linearity', 'render'")
    H, W = rig.projector.intrinsics.shape
    stack = gc.encode(W, H)
    n_bits = len(stack) // 2
    wb_r = _check_patterns(
        capture, np.stack([np.ones((H, W), np.float32), np.zeros((H, W), np.float32)])
    )
    renders = 2
    dec = gc.GrayDecoder(
        (H, W),
        wb_r.shape[1:],
        black_threshold=black_threshold,
        white_threshold=white_threshold,
        keep_diff=subpixel,
    )
    kept = [] if keep_frames else None
    for k in range(n_bits):
        if inverses == "linearity":
            pat_r = _check_patterns(capture, stack[2 * k : 2 * k + 1].astype(np.float32) / 255.0)
            pair_r = np.concatenate([pat_r, gc.inverses_by_linearity(pat_r, wb_r[0], wb_r[1])])
            renders += 1
        else:
            pair_r = _check_patterns(capture, stack[2 * k : 2 * k + 2].astype(np.float32) / 255.0)
            renders += 2
        pair = np.asarray(capture.sense(pair_r))
        dec.add_pair(k, pair[0], pair[1])
        if kept is not None:
            kept.append(pair)
    white, black = np.asarray(capture.sense(wb_r))
    dec.add_white_black(white, black)
    result = dec.result(require_reliable=require_reliable)
    if subpixel:
        result = gc.refine_subpixel_from_diff(result, dec.diff)
    cloud = triangulate(rig, Correspondences.from_gray(result), method=method)
    depth = depth_at_proj_pixels(cloud, rig.guide)
    frames = {"white": white, "black": black}
    if kept is not None:
        frames["images"] = np.concatenate(kept)
    return GrayScan(
        decode=result,
        cloud=cloud,
        depth=depth,
        renders=renders,
        frames=frames,
    )


def dot_scan(
    capture,
    rig: Rig,
    proj_uv,
    *,
    depth_range: tuple[float, float],
    exact: bool = False,
    radius: float = 0.0,
    min_proj_spacing: float = 8.0,
    min_cam_spacing: float = 6.0,
    tol: float = 2.0,
    rel_threshold: float = 0.02,
    abs_threshold: float = 0.02,
    batch: int = 8,
) -> DotScan:
    """Scan dots (one projector pixel or a small disk each), multiplexed or one per frame.

    Parameters
    ----------
    capture : object with ``render`` and ``sense``
    rig : Rig
    proj_uv : (n, 2) projector pixel coordinates of the dots (n >= 1)
    depth_range : (near, far) projector z-depths bounding the scene (m): sets the epipolar
        segments used for scheduling and matching
    exact : bool
        One dot per frame (reference mode) instead of multiplexed frames.
    radius : float
        Dot radius in projector pixels (0 = one pixel).
    min_proj_spacing, min_cam_spacing, tol : float
        Scheduling spacings (projector px, camera px) and the matching tolerance (camera px).
    rel_threshold, abs_threshold : float
        Blob detection thresholds (relative to the frame's brightest dot; absolute in frame
        units). The relative one stays low because a multiplexed frame mixes bright and dark
        surfaces: a dot on dark soil must not be lost next to one on a bright rock.
    batch : int
        Frames rendered per ``capture.render`` call (memory bound only).

    Returns
    -------
    DotScan
    """
    check_rig(rig)
    proj_uv = np.asarray(proj_uv, float)
    if proj_uv.ndim != 2 or proj_uv.shape[1] != 2 or len(proj_uv) == 0:
        raise ValueError(
            f"dot set is empty or not (n, 2): got shape {proj_uv.shape}; a dot scan "
            "needs at least one dot"
        )
    H, W = rig.projector.intrinsics.shape
    schedule = _dots.schedule_dots(
        rig,
        proj_uv,
        depth_range=depth_range,
        min_proj_spacing=min_proj_spacing,
        min_cam_spacing=min_cam_spacing,
        exact=exact,
    )
    black = np.asarray(capture.sense(_check_patterns(capture, np.zeros((1, H, W), np.float32))))[0]
    segments = _dots.epipolar_segments(rig, proj_uv, depth_range)
    cam_uv = np.full((len(proj_uv), 2), np.nan)
    n_ghosts = 0
    for start in range(0, len(schedule), batch):
        group = schedule[start : start + batch]
        pats = np.stack([_dots.dot_pattern((H, W), proj_uv[f], radius=radius) for f in group])
        frames = np.asarray(capture.sense(_check_patterns(capture, pats)))
        for f, frame in zip(group, frames):
            det = _dots.detect_dots(
                frame, background=black, rel_threshold=rel_threshold, abs_threshold=abs_threshold
            )
            m = _dots.match_dots(det, segments[f], tol=tol)
            cam_uv[f[m.dot]] = m.cam_uv
            n_ghosts += m.n_ghosts
    found = np.isfinite(cam_uv).all(axis=1)
    cloud = triangulate(rig, Correspondences(cam_uv[found], proj_uv[found]), method="rays")
    depth = depth_at_proj_pixels(cloud, rig.guide)
    return DotScan(
        proj_uv=proj_uv,
        found=found,
        cam_uv=cam_uv,
        cloud=cloud,
        depth=depth,
        renders=len(schedule) + 1,
        frames_per_dot=schedule,
        n_ghosts=n_ghosts,
    )


def plan_pixels(
    guide_image: np.ndarray, k: int, *, planner: str, rng, valid=None, **opts
) -> np.ndarray:
    """Guide pixels (rows, cols) chosen by a sampling-study planner: (k, 2) int (row, col).

    ``valid`` (bool (H, W)) restricts the choice, e.g. to pixels the projector can light.
    """
    from simlunar.planner import plan

    img = np.asarray(guide_image, float)
    if valid is not None:
        # planners see a zero image where nothing can be measured
        img = np.where(valid, img, 0.0)
    p = plan(planner, int(k), image=img, shape=img.shape, rng=rng, **opts)
    rc = np.stack([np.asarray(p.rows), np.asarray(p.cols)], axis=-1).astype(np.int64)
    return rc


#: rescan planners that rank pixels by the gray-code scan itself rather than by the guide
#: image (``ambiguity_enhancement`` only: they need the scan)
SCAN_PLANNERS = ("low_contrast",)


def low_contrast_pixels(gray: GrayScan, k: int, *, rng) -> np.ndarray:
    """The ``k`` guide pixels the gray-code scan saw with the least contrast: (k, 2) (row, col).

    Each projector pixel (= guide pixel) gets the lowest ``white - black`` contrast of the lit
    camera pixels whose gray code decodes to it (whether or not every bit was reliable: a
    dim pixel's code is what it is, and a wrong code puts a wrong depth at the pixel it names);
    the ``k`` lowest are rescanned, ties in random order. Projector pixels no lit camera pixel
    decodes to come last: the camera cannot see a dot there either. The threshold ablation
    (docs/scanner.md) finds most of the gray code's squared error in its lowest-contrast
    pixels.
    """
    dec = gray.decode
    if dec.contrast is None:
        raise ValueError("low_contrast needs a decode with its contrast (GrayDecoder.result)")
    H, W = dec.proj_shape
    if not 1 <= int(k) <= H * W:
        raise ValueError(f"k must be in 1..{H * W}, got {k}")
    col, row = dec.decoded_index()
    ok = dec.lit & (col < W) & (row < H)
    lowest = np.full(H * W, np.inf)
    np.minimum.at(lowest, (row[ok] * W + col[ok]).ravel(), dec.contrast[ok].ravel())
    tie = np.random.default_rng(rng).random(H * W)
    order = np.lexsort((tie, lowest))[: int(k)]
    return np.stack([order // W, order % W], axis=-1).astype(np.int64)


def fill_holes(depth: np.ndarray, *, outside: str = "nearest") -> np.ndarray:
    """Delaunay-linear reconstruction of a depth map with NaN holes to the full grid."""
    from simlunar.reconstruction import reconstruct

    r, c = np.nonzero(np.isfinite(depth))
    if len(r) == 0:
        from simlunar.errors import NothingMeasuredError

        raise NothingMeasuredError(
            "the scan measured no pixel (nothing decoded: projector too faint against the "
            "sun or the thresholds, or the camera sees no projected pixel), so there is no "
            "depth to reconstruct"
        )
    return reconstruct(
        np.stack([r, c], axis=-1).astype(float), depth[r, c], depth.shape, outside=outside
    )


@dataclass(frozen=True, eq=False)
class ScanResult:
    """Output of a scan mode.

    Attributes
    ----------
    mode : str
    depth : (H, W) guide-view depth, reconstructed to the full grid (m)
    measured : (H, W) guide-view depth of the measured pixels only (NaN holes)
    renders : int total rendered frames
    gray : GrayScan or None
    dots : DotScan or None
    planned_rc : (k, 2) int or None guide pixels chosen by the planner
    """

    mode: str
    depth: np.ndarray
    measured: np.ndarray
    renders: int
    gray: GrayScan | None = None
    dots: DotScan | None = None
    planned_rc: np.ndarray | None = None


def scan_gray_code(
    capture, rig: Rig, *, gray_opts: dict | None = None, outside: str = "nearest"
) -> ScanResult:
    """Mode ``gray_code``: full scan, holes filled by Delaunay-linear reconstruction."""
    g = gray_code_scan(capture, rig, **(gray_opts or {}))
    return ScanResult("gray_code", fill_holes(g.depth, outside=outside), g.depth, g.renders, gray=g)


def scan_ambiguity_enhancement(
    capture,
    rig: Rig,
    *,
    guide_image: np.ndarray,
    planner: str,
    rng,
    depth_range: tuple[float, float],
    budget: float = 0.1,
    gray: GrayScan | None = None,
    gray_opts: dict | None = None,
    dot_opts: dict | None = None,
    planner_opts: dict | None = None,
    outside: str = "nearest",
) -> ScanResult:
    """Mode ``ambiguity_enhancement``: gray code, then rescan a planned ``budget`` of pixels with dots.

    The dots replace the gray-code depth where they were found; the fused map is reconstructed
    to the full grid. ``budget`` is the fraction of guide pixels rescanned (paper: ~10%).
    """
    g = gray if gray is not None else gray_code_scan(capture, rig, **(gray_opts or {}))
    rc, d = _planned_dot_scan(
        capture, rig, guide_image, planner, rng, depth_range, budget, dot_opts, planner_opts, g
    )
    fused = g.depth.copy()
    hit = np.isfinite(d.depth)
    fused[hit] = d.depth[hit]
    renders = d.renders + (g.renders if gray is None else 0)
    return ScanResult(
        "ambiguity_enhancement",
        fill_holes(fused, outside=outside),
        fused,
        renders,
        gray=g,
        dots=d,
        planned_rc=rc,
    )


def scan_data_reduction(
    capture,
    rig: Rig,
    *,
    guide_image: np.ndarray,
    planner: str,
    rng,
    depth_range: tuple[float, float],
    budget: float = 0.1,
    dot_opts: dict | None = None,
    planner_opts: dict | None = None,
    outside: str = "nearest",
) -> ScanResult:
    """Mode ``data_reduction``: only a planned sparse dot set, reconstructed Delaunay-linearly."""
    rc, d = _planned_dot_scan(
        capture, rig, guide_image, planner, rng, depth_range, budget, dot_opts, planner_opts
    )
    return ScanResult(
        "data_reduction",
        fill_holes(d.depth, outside=outside),
        d.depth,
        d.renders,
        dots=d,
        planned_rc=rc,
    )


def _planned_dot_scan(
    capture, rig, guide_image, planner, rng, depth_range, budget, dot_opts, planner_opts, gray=None
):
    """Plan ``budget`` of the guide pixels (from the guide image, or from the gray-code scan
    ``gray`` for a :data:`SCAN_PLANNERS` planner) and scan them with dots.

    Returns the planned pixels (k, 2) as (row, col) and the :class:`DotScan`.
    """
    H, W = rig.projector.intrinsics.shape
    k = _budget_k(budget, H * W)
    if planner in SCAN_PLANNERS:
        if gray is None:
            raise ValueError(
                f"planner {planner!r} ranks the pixels of a gray-code scan: use it with the "
                "ambiguity_enhancement mode"
            )
        if planner_opts:
            raise ValueError(f"planner {planner!r} takes no options, got {sorted(planner_opts)}")
        rc = low_contrast_pixels(gray, k, rng=rng)
    else:
        rc = plan_pixels(guide_image, k, planner=planner, rng=rng, **(planner_opts or {}))
    # guide pixel (r, c) is projector pixel (r, c): its centre is (u, v) = (c + .5, r + .5)
    d = dot_scan(
        capture,
        rig,
        np.c_[rc[:, 1] + 0.5, rc[:, 0] + 0.5],
        depth_range=depth_range,
        **(dot_opts or {}),
    )
    return rc, d


def _budget_k(budget: float, n: int) -> int:
    if not 0 < budget <= 1:
        raise ValueError(f"budget must be a fraction in (0, 1], got {budget}")
    return max(1, round(budget * n))


MODES = {
    "gray_code": scan_gray_code,
    "ambiguity_enhancement": scan_ambiguity_enhancement,
    "data_reduction": scan_data_reduction,
}


def scan(mode: str, capture, rig: Rig, **kw) -> ScanResult:
    """Run a scan mode by name (``gray_code``, ``ambiguity_enhancement``, ``data_reduction``)."""
    try:
        fn = MODES[mode]
    except KeyError:
        raise ValueError(f"unknown scan mode {mode!r}; valid: {sorted(MODES)}") from None
    return fn(capture, rig, **kw)
