"""Structured-light scans: a full gray-code scan and a dot scan of given projector pixels.

The scans are NumPy-only and drive any *capture* object (the
:class:`~simlunar.render.capture.Capture` protocol) with two methods:

``capture.render(patterns) -> (n, rows, cols) float``
    Noise-free camera images of the scene under ``n`` projector patterns (projector shape
    (H, W), values in [0, 1]). Each pattern counts as one render.
``capture.sense(images) -> (n, rows, cols) float``
    Captured frames: sensor noise, quantisation and response applied per frame.

:class:`simlunar.render.capture.RenderCapture` is the Mitsuba-backed capture; tests use NumPy
ones. The scan *modes* (gray code, ambiguity enhancement, data reduction) are modes of the
structured-light sensor, :mod:`simlunar.sensors.structured_light`.
Inverse patterns come from linearity of light transport (``bits + 2`` renders instead of
``2 * bits + 2``) unless ``inverses="render"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simlunar.geometry import Rig
from simlunar.progress import stage
from simlunar.registry import Options, option
from simlunar.scanner import dots as _dots
from simlunar.scanner import gray_code as gc
from simlunar.scanner.coded import FullFieldCoding, render_checked, scan_inputs
from simlunar.scanner.gray_errors import bit_error_table
from simlunar.scanner.scheduling import schedule_dots
from simlunar.scanner.subpixel import refine_subpixel_from_diff
from simlunar.scanner.triangulate import (
    Correspondences,
    PointCloud,
    check_rig,
    depth_at_proj_pixels,
    triangulate,
)

__all__ = [
    "SCAN_PLANNERS",
    "CodedScan",
    "DotOptions",
    "DotScan",
    "GrayCodeOptions",
    "GrayCoding",
    "GrayScan",
    "coded_scan",
    "dot_scan",
    "gray_code_scan",
    "low_contrast_pixels",
    "triangulated",
]

#: how a gray-code scan obtains the inverse-pattern images, and how it triangulates
_INVERSES = ("linearity", "render")
_METHODS = ("plane", "rays")


def _valid(names) -> str:
    return ", ".join(map(repr, names))


@dataclass(frozen=True)
class GrayCodeOptions(Options):
    """Options of :func:`gray_code_scan` (OpenCV's decoder conventions).

    ``keep_frames`` keeps the captured stack in ``GrayScan.frames["images"]`` (white and black
    are always kept); it is not a YAML option: the study sets it when scans are exported.
    """

    # frames are exposed so the white frame's bright pixels sit at 0.8 of the range
    # (CaptureOptions.target_level): a threshold at or above it marks every pixel invalid
    black_threshold: float = option(
        0.05,
        doc="OpenCV's validity threshold (frame units; below 0.8, the white level)",
        ge=0.0,
        lt=0.8,
    )
    white_threshold: float = option(
        0.01, doc="OpenCV's bit-reliability threshold (frame units; below 0.8)", ge=0.0, lt=0.8
    )
    inverses: str = option(
        "linearity", doc="inverse patterns by linearity of light or rendered", choices=_INVERSES
    )
    method: str = option("plane", doc="triangulation: column plane or rays", choices=_METHODS)
    require_reliable: bool = option(
        True, doc="a pixel with an unreliable bit is invalid (OpenCV's behaviour)"
    )
    subpixel: bool = option(
        False,
        doc="sub-pixel stripe-edge refinement of the decoded columns and rows "
        "(simlunar.scanner.subpixel.refine_subpixel) instead of projector pixel centres",
    )
    keep_frames: bool = False


@dataclass(frozen=True)
class DotOptions(Options):
    """Options of :func:`dot_scan`.

    The relative blob threshold stays low because a multiplexed frame mixes bright and dark
    surfaces: a dot on dark soil must not be lost next to one on a bright rock.
    """

    exact: bool = option(False, doc="one dot per frame (reference mode) instead of multiplexed")
    radius: float = option(0.0, doc="dot radius in the projector (0 = one pixel)", unit="px", ge=0)
    min_proj_spacing: float = option(
        8.0, doc="scheduling spacing in the projector", unit="px", ge=0
    )
    min_cam_spacing: float = option(6.0, doc="scheduling spacing in the camera", unit="px", ge=0)
    tol: float = option(2.0, doc="matching tolerance in the camera", unit="px", ge=0)
    rel_threshold: float = option(
        0.02, doc="blob threshold relative to the frame's brightest dot", ge=0, le=1
    )
    abs_threshold: float = option(0.02, doc="absolute blob threshold (frame units)", ge=0, le=1)
    batch: int = option(8, doc="frames rendered per capture.render call (memory only)", ge=1)


@dataclass(frozen=True, eq=False)
class CodedScan:
    """Result of a full-field coded scan (gray code, phase shift, ...).

    Attributes
    ----------
    decode : the coding's decode (camera view): ``valid``, ``lit``, ``contrast``, ``col``,
        ``row``, ``proj_shape``, ``proj_uv()``, ``decoded_index()``
        (:class:`~simlunar.scanner.gray_code.GrayDecode`, ...)
    cloud : PointCloud of every valid camera pixel
    depth : (H, W) float64 z-depth in the guide (projector) view, NaN holes
    renders : int number of rendered frames
    frames : dict of the captured 'white' and 'black' frames and, with ``keep_frames``, the
        'images' (the coding's stack in export order, white and black excluded)
    coding : the coding object that made the scan (:data:`simlunar.scanner.codings.CODINGS`;
        its ``options`` are the scan's), or None
    """

    decode: object
    cloud: PointCloud
    depth: np.ndarray
    renders: int
    frames: dict = field(repr=False)
    coding: object = None


#: the gray-code scan's result (a :class:`CodedScan` whose decode is a ``GrayDecode``)
GrayScan = CodedScan


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


def gray_code_scan(capture, rig: Rig, options: GrayCodeOptions | None = None) -> GrayScan:
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
    options : GrayCodeOptions, optional
        Thresholds, inverses, triangulation method, sub-pixel refinement, kept frames.

    Returns
    -------
    GrayScan
    """
    o, (H, W) = scan_inputs(rig, options, GrayCodeOptions)
    stack = gc.encode(W, H)
    n_bits = len(stack) // 2
    wb_r = render_checked(
        capture, np.stack([np.ones((H, W), np.float32), np.zeros((H, W), np.float32)])
    )
    renders = 2
    dec = gc.GrayDecoder(
        (H, W),
        wb_r.shape[1:],
        black_threshold=o.black_threshold,
        white_threshold=o.white_threshold,
        keep_diff=o.subpixel,
    )
    kept = [] if o.keep_frames else None
    for k in range(n_bits):
        if o.inverses == "linearity":
            pat_r = render_checked(capture, stack[2 * k : 2 * k + 1].astype(np.float32) / 255.0)
            pair_r = np.concatenate([pat_r, gc.inverses_by_linearity(pat_r, wb_r[0], wb_r[1])])
            renders += 1
        else:
            pair_r = render_checked(capture, stack[2 * k : 2 * k + 2].astype(np.float32) / 255.0)
            renders += 2
        pair = np.asarray(capture.sense(pair_r))
        dec.add_pair(k, pair[0], pair[1])
        if kept is not None:
            kept.append(pair)
    white, black = np.asarray(capture.sense(wb_r))
    dec.add_white_black(white, black)
    result = dec.result(require_reliable=o.require_reliable)
    if o.subpixel:
        result = refine_subpixel_from_diff(result, dec.diff)
    images = None if kept is None else np.concatenate(kept)
    return coded_scan(rig, result, white, black, images, renders=renders, coding=GrayCoding(o))


def triangulated(rig: Rig, decode, method: str) -> tuple[PointCloud, np.ndarray]:
    """The point cloud of a full-field decode's valid pixels and its (H, W) depth in the
    guide view (NaN holes): what every coded scan does after decoding.

    Parameters
    ----------
    rig : Rig
    decode : a decode with ``valid`` and ``proj_uv()`` (module :mod:`~simlunar.scanner.codings`)
    method : "plane" or "rays" (:func:`simlunar.scanner.triangulate.triangulate`)
    """
    cloud = triangulate(rig, Correspondences.from_gray(decode), method=method)
    return cloud, depth_at_proj_pixels(cloud, rig.guide)


def coded_scan(rig: Rig, decode, white, black, images, *, renders: int, coding) -> CodedScan:
    """Triangulate a full-field ``decode`` (:func:`triangulated`, with ``coding.method``) and
    bundle it with the sensed frames: how every coded scan ends.

    Parameters
    ----------
    rig : Rig
    decode : a decode with ``valid`` and ``proj_uv()``
    white, black : ndarray, shape (H, W)
        The sensed all-on and all-off frames.
    images : ndarray, shape (n, H, W), or None
        The sensed pattern frames, kept when the options ask (None: not kept).
    renders : int
        Patterns rendered.
    coding : the coding that scanned (its ``options.method`` triangulates)
    """
    cloud, depth = triangulated(rig, decode, coding.method)
    frames = {"white": white, "black": black}
    if images is not None:
        frames["images"] = images
    return CodedScan(
        decode=decode, cloud=cloud, depth=depth, renders=renders, frames=frames, coding=coding
    )


class GrayCoding(FullFieldCoding):
    """The gray code as a coding of :data:`simlunar.scanner.codings.CODINGS`.

    Parameters
    ----------
    options : GrayCodeOptions, optional
    """

    frame_order = "OpenCV GrayCodePattern.generate() order, then white, black"
    _scan = staticmethod(gray_code_scan)

    def __init__(self, options: GrayCodeOptions | None = None) -> None:
        self.options = options or GrayCodeOptions()

    @staticmethod
    def _bits(proj_shape) -> tuple[int, int]:
        H, W = (int(proj_shape[0]), int(proj_shape[1]))
        return gc.num_bits(W), gc.num_bits(H)

    def frames(self, proj_shape) -> int:
        """Captured frames: (pattern, inverse) per bit, then white and black."""
        return 2 * sum(self._bits(proj_shape)) + 2

    def frame_names(self, proj_shape) -> list[str]:
        return gc.frame_names(*self._bits(proj_shape))

    def patterns(self, proj_shape) -> np.ndarray:
        """(frames, H, W) float32: :func:`~simlunar.scanner.gray_code.encode`, white, black."""
        H, W = (int(proj_shape[0]), int(proj_shape[1]))
        white, black = gc.white_black(W, H)
        return np.concatenate([gc.encode(W, H), white[None], black[None]]).astype(np.float32) / 255

    def decode(self, frames, proj_shape) -> gc.GrayDecode:
        """Decode a whole stack in :meth:`patterns` order (white and black last)."""
        frames = np.asarray(frames)
        o = self.options
        return gc.decode(
            frames[:-2],
            frames[-2],
            frames[-1],
            proj_shape=proj_shape,
            black_threshold=o.black_threshold,
            white_threshold=o.white_threshold,
            require_reliable=o.require_reliable,
        )

    def export_meta(self, decode) -> dict:
        o = self.options
        return {
            "n_col_bits": int(decode.n_col_bits),
            "n_row_bits": int(decode.n_row_bits),
            "black_threshold": float(o.black_threshold),
            "white_threshold": float(o.white_threshold),
            "opencv_black_threshold_8bit": round(255 * float(o.black_threshold)),
            "opencv_white_threshold_8bit": round(255 * float(o.white_threshold)),
            "inverses": str(o.inverses),
            "subpixel": bool(o.subpixel),
            "triangulation": str(o.method),
        }

    def truth_scores(self, scan: CodedScan, truth: dict, mask=None) -> dict[str, float]:
        """Bit error rates ``ber_c<i>`` / ``ber_r<i>``
        (:func:`simlunar.scanner.gray_errors.bit_error_table`)."""
        return bit_error_table(scan.decode, truth, mask)


def dot_scan(
    capture,
    rig: Rig,
    proj_uv,
    *,
    depth_range: tuple[float, float],
    options: DotOptions | None = None,
) -> DotScan:
    """Scan dots (one projector pixel or a small disk each), multiplexed or one per frame.

    Parameters
    ----------
    capture : object with ``render`` and ``sense``
    rig : Rig
    proj_uv : (n, 2) projector pixel coordinates of the dots (n >= 1)
    depth_range : (near, far) projector z-depths bounding the scene (m): sets the epipolar
        segments used for scheduling and matching
    options : DotOptions, optional
        Dot size, scheduling spacings, matching tolerance, detection thresholds, batch.

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
    o = options or DotOptions()
    H, W = rig.projector.intrinsics.shape
    schedule = schedule_dots(
        rig,
        proj_uv,
        depth_range=depth_range,
        min_proj_spacing=o.min_proj_spacing,
        min_cam_spacing=o.min_cam_spacing,
        exact=o.exact,
    )
    # the black frame, then the scheduled dot frames (a capture counts each into the stage)
    with stage("dot frames", total=1 + len(schedule), unit="frames"):
        return _dot_frames(capture, rig, proj_uv, schedule, depth_range, o, (H, W))


def _dot_frames(capture, rig: Rig, proj_uv, schedule, depth_range, o: DotOptions, shape):
    """:func:`dot_scan` after scheduling: capture, detect, match and triangulate the dots."""
    H, W = shape
    black = np.asarray(capture.sense(render_checked(capture, np.zeros((1, H, W), np.float32))))[0]
    segments = _dots.epipolar_segments(rig, proj_uv, depth_range)
    cam_uv = np.full((len(proj_uv), 2), np.nan)
    n_ghosts = 0
    for start in range(0, len(schedule), o.batch):
        group = schedule[start : start + o.batch]
        pats = np.stack([_dots.dot_pattern((H, W), proj_uv[f], radius=o.radius) for f in group])
        frames = np.asarray(capture.sense(render_checked(capture, pats)))
        for f, frame in zip(group, frames):
            det = _dots.detect_dots(
                frame,
                background=black,
                rel_threshold=o.rel_threshold,
                abs_threshold=o.abs_threshold,
            )
            m = _dots.match_dots(det, segments[f], tol=o.tol)
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
