"""The bit-plane code's decoder, options, scan and coding: the gray code of the paper and
OpenCV, and any other :class:`~simlunar.scanner.bitcodes.BitCode` (the options' ``code``).

The patterns and the codes are :mod:`simlunar.scanner.bitcodes` (re-exported here). The
decision rules follow OpenCV contrib ``structured_light.GrayCodePattern`` (its documentation and
source), so gray-code stacks made here decode with OpenCV and the other way round:

* a camera pixel is valid if ``white - black > black_threshold``; a bit is 1 if
  ``pattern > inverse`` and unreliable if ``|pattern - inverse| < white_threshold``;
* the code word read from the bits names the index (:meth:`BitCode.index`: for the gray code,
  gray to binary); a decoded index outside the pattern is invalid.

Thresholds are in the units of the images passed in (OpenCV's defaults 40 and 5 are for 8-bit
images; for float images in [0, 1] use about 40/255 and 5/255).

The scan (:func:`gray_code_scan`) drives any *capture* (the
:class:`~simlunar.render.capture.Capture` protocol: ``render(patterns)`` noise-free images, one
render per pattern, and ``sense(images)`` captured frames). Inverse patterns come from
linearity of light transport (``bits + 2`` renders instead of ``2 * bits + 2``) unless
``inverses="render"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simlunar.registry import Options, option
from simlunar.scanner.bitcodes import (
    GRAY,
    BitCode,
    bit_planes,
    encode,
    frame_names,
    gray,
    gray_to_binary,
    interleave,
    inverses_by_linearity,
    num_bits,
    positive_patterns,
    white_black,
)
from simlunar.scanner.coded import StackFunctions, WhiteBlackLastCoding, render_checked, scan_inputs
from simlunar.scanner.gray_errors import bit_error_table
from simlunar.scanner.result import CodedScan, coded_scan
from simlunar.scanner.subpixel import refine_subpixel_from_diff

__all__ = [
    "GrayCodeOptions",
    "GrayCoding",
    "GrayDecode",
    "GrayDecoder",
    "GrayScan",
    "bit_planes",
    "decode",
    "encode",
    "frame_names",
    "gray",
    "gray_code_scan",
    "gray_to_binary",
    "interleave",
    "inverses_by_linearity",
    "num_bits",
    "positive_patterns",
    "white_black",
]

#: how a bit-plane scan obtains the inverse-pattern images, and how it triangulates
_INVERSES = ("linearity", "render")
_METHODS = ("plane", "rays")

#: the gray-code scan's result (a :class:`CodedScan` whose decode is a ``GrayDecode``)
GrayScan = CodedScan


@dataclass(frozen=True, eq=False)
class GrayDecode:
    """Dense result of decoding a gray-code stack seen by a camera.

    All arrays are over camera pixels (rows, cols).

    Attributes
    ----------
    col, row : int64
        Decoded projector column and row; -1 where ``valid`` is False.
    valid : bool
        Lit (``white - black > black_threshold``), every bit reliable and the decoded index
        inside the projector.
    lit : bool
        ``white - black > black_threshold`` (False in projector shadow / outside the projection).
    bits : (n_col_bits + n_row_bits, rows, cols) uint8
        Decoded gray-code bits (MSB first, columns then rows).
    reliable : (n_col_bits + n_row_bits, rows, cols) bool
        ``|pattern - inverse| >= white_threshold`` per bit.
    n_col_bits, n_row_bits : int
    proj_shape : (int, int)
        Projector (height, width).
    subpixel : (rows, cols, 2) float64 or None
        Sub-pixel projector coordinates (u, v) from stripe-edge refinement
        (:func:`simlunar.scanner.subpixel.refine_subpixel`), each inside its decoded pixel; NaN where a pixel could not be
        refined (its pixel centre is used). None: not refined.
    contrast : (rows, cols) float32 or None
        ``white - black`` per camera pixel (frame units): how brightly the projector lights
        what the pixel sees (the ``low_contrast`` rescan planner ranks by it).
    code : BitCode
        The code the bits are words of (:data:`~simlunar.scanner.bitcodes.GRAY` unless the
        scan said otherwise).
    """

    col: np.ndarray
    row: np.ndarray
    valid: np.ndarray
    lit: np.ndarray
    bits: np.ndarray
    reliable: np.ndarray
    n_col_bits: int
    n_row_bits: int
    proj_shape: tuple[int, int]
    subpixel: np.ndarray | None = None
    contrast: np.ndarray | None = None
    code: BitCode = GRAY

    @property
    def shape(self) -> tuple[int, int]:
        return self.valid.shape  # type: ignore[return-value]

    def decoded_index(self) -> tuple[np.ndarray, np.ndarray]:
        """``(col, row)`` int64 that every camera pixel's bits name, valid or not (``col``
        and ``row`` hold -1 where the pixel is invalid)."""
        ncb = self.n_col_bits
        return self.code.index(self.bits[:ncb]), self.code.index(self.bits[ncb:])

    def proj_uv(self) -> np.ndarray:
        """(rows, cols, 2) projector coordinates (u, v); NaN where invalid.

        Pixel centres ``(col + 0.5, row + 0.5)``, or the refined coordinates where
        ``subpixel`` has them.
        """
        uv = np.stack([self.col + 0.5, self.row + 0.5], axis=-1).astype(float)
        if self.subpixel is not None:
            uv = np.where(np.isfinite(self.subpixel), self.subpixel, uv)
        uv[~self.valid] = np.nan
        return uv


class GrayDecoder:
    """Streaming bit-plane (gray-code) decoder: frames are added as they are captured.

    Holds per camera pixel only the decoded bits, their reliability and (for sub-pixel
    refinement) the pattern-minus-inverse signal of each bit, never the frame stack, so a
    scan's memory does not grow with its number of frames. :func:`decode` is this class fed
    with a whole stack; both give identical results.

    Parameters
    ----------
    proj_shape : (H, W)
        Projector pattern shape (height, width).
    cam_shape : (rows, cols)
        Camera frame shape.
    black_threshold, white_threshold : float
        OpenCV's thresholds, in the units of the frames (see :func:`decode`).
    keep_diff : bool
        Keep each bit's ``pattern - inverse`` signal (float32 for float32 frames, else
        float64) for :func:`simlunar.scanner.subpixel.refine_subpixel_from_diff`.
    code : BitCode
        The code of the patterns (the gray code by default).
    """

    def __init__(
        self,
        proj_shape: tuple[int, int],
        cam_shape: tuple[int, int],
        *,
        black_threshold: float = 40.0,
        white_threshold: float = 5.0,
        keep_diff: bool = False,
        code: BitCode = GRAY,
    ) -> None:
        self.code = code
        self.proj_shape = (int(proj_shape[0]), int(proj_shape[1]))
        self.cam_shape = (int(cam_shape[0]), int(cam_shape[1]))
        H, W = self.proj_shape
        self.n_col_bits, self.n_row_bits = num_bits(W), num_bits(H)
        self.n_bits = self.n_col_bits + self.n_row_bits
        self.black_threshold = float(black_threshold)
        self.white_threshold = float(white_threshold)
        self.bits = np.zeros((self.n_bits, *self.cam_shape), np.uint8)
        self.reliable = np.zeros((self.n_bits, *self.cam_shape), bool)
        self.keep_diff = bool(keep_diff)
        self.diff: np.ndarray | None = None
        self._seen = np.zeros(self.n_bits, bool)
        self.lit: np.ndarray | None = None
        self.contrast: np.ndarray | None = None

    def _frame(self, name: str, a) -> np.ndarray:
        a = np.asarray(a)
        if a.shape != self.cam_shape:
            raise ValueError(f"{name} frame {a.shape} must match the camera shape {self.cam_shape}")
        return a

    def add_pair(self, bit: int, pattern, inverse) -> None:
        """Add the captured (pattern, inverse) frames of gray bit ``bit``.

        ``bit`` counts column bits MSB first, then row bits MSB first (the pair index of the
        :func:`encode` stack).
        """
        bit = int(bit)
        if not 0 <= bit < self.n_bits:
            raise ValueError(f"bit must be in 0..{self.n_bits - 1}, got {bit}")
        p = self._frame("pattern", pattern)
        i = self._frame("inverse", inverse)
        # the decision is made in float64 whatever the frames' type
        d = np.subtract(p, i, dtype=np.float64)
        np.greater(d, 0.0, out=self.bits[bit], casting="unsafe")
        np.greater_equal(np.abs(d), self.white_threshold, out=self.reliable[bit])
        if self.keep_diff:
            if self.diff is None:
                dt = np.float64 if np.result_type(p, i) == np.float64 else np.float32
                self.diff = np.zeros((self.n_bits, *self.cam_shape), dt)
            self.diff[bit] = d
        self._seen[bit] = True

    def add_white_black(self, white, black) -> None:
        """Add the captured all-white and all-black frames."""
        w = self._frame("white", white)
        b = self._frame("black", black)
        contrast = np.subtract(w, b, dtype=np.float64)
        self.lit = contrast > self.black_threshold
        self.contrast = contrast.astype(np.float32)

    def result(self, *, require_reliable: bool = True) -> GrayDecode:
        """The decode of the frames added so far (every pair and white/black are needed)."""
        missing = np.flatnonzero(~self._seen)
        if missing.size or self.lit is None:
            what = [f"bit {int(k)}" for k in missing] + (
                ["white/black"] if self.lit is None else []
            )
            raise ValueError(f"gray-code decode is missing frames: {', '.join(what)}")
        H, W = self.proj_shape
        ncb = self.n_col_bits
        col = self.code.index(self.bits[:ncb])
        row = self.code.index(self.bits[ncb:])
        valid = self.lit & (col < W) & (row < H)
        if require_reliable:
            valid &= np.all(self.reliable, axis=0)
        col[~valid] = -1
        row[~valid] = -1
        return GrayDecode(
            col=col,
            row=row,
            valid=valid,
            lit=self.lit,
            bits=self.bits,
            reliable=self.reliable,
            n_col_bits=ncb,
            n_row_bits=self.n_row_bits,
            proj_shape=(H, W),
            contrast=self.contrast,
            code=self.code,
        )


def decode(
    images: np.ndarray,
    white: np.ndarray,
    black: np.ndarray,
    *,
    proj_shape: tuple[int, int],
    black_threshold: float = 40.0,
    white_threshold: float = 5.0,
    require_reliable: bool = True,
    code: BitCode = GRAY,
) -> GrayDecode:
    """Decode a bit-plane (gray-code) image stack into per-pixel projector correspondences.

    Parameters
    ----------
    images : (2 * (num_bits(W) + num_bits(H)), rows, cols) array
        Captured (pattern, inverse) pairs in :func:`encode` order.
    white, black : (rows, cols) array
        Captured all-white and all-black frames.
    proj_shape : (H, W)
        Projector pattern shape (height, width).
    black_threshold, white_threshold : float
        OpenCV's thresholds, in the units of the images.
    require_reliable : bool
        If True (OpenCV's behaviour) a pixel with any unreliable bit is invalid.
    code : BitCode
        The code of the patterns (the gray code by default).

    Returns
    -------
    GrayDecode
    """
    H, W = (int(proj_shape[0]), int(proj_shape[1]))
    ncb, nrb = num_bits(W), num_bits(H)
    images = np.asarray(images)
    white = np.asarray(white)
    black = np.asarray(black)
    n_expected = 2 * (ncb + nrb)
    if images.ndim != 3 or images.shape[0] != n_expected:
        raise ValueError(
            f"images must be a ({n_expected}, rows, cols) gray-code stack for a {W}x{H} projector "
            f"({ncb} column + {nrb} row bits, pattern and inverse each), got shape {images.shape}"
        )
    if white.shape != images.shape[1:] or black.shape != images.shape[1:]:
        raise ValueError(
            f"white {white.shape} and black {black.shape} frames must match the "
            f"camera shape {images.shape[1:]}"
        )
    dec = GrayDecoder(
        (H, W),
        images.shape[1:],
        black_threshold=black_threshold,
        white_threshold=white_threshold,
        code=code,
    )
    for k in range(ncb + nrb):
        dec.add_pair(k, images[2 * k], images[2 * k + 1])
    dec.add_white_black(white, black)
    return dec.result(require_reliable=require_reliable)


@dataclass(frozen=True)
class GrayCodeOptions(Options):
    """Options of :func:`gray_code_scan` (OpenCV's decoder conventions).

    ``keep_frames`` keeps the captured stack in ``GrayScan.frames["images"]`` (white and black
    are always kept); it is not a YAML option: the study sets it when scans are exported.
    ``code`` is the bit-plane code (not a YAML option either: a coding of its own, as the
    plain binary code, sets it in its options class).
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
    code: BitCode = GRAY


def gray_code_scan(capture, rig, options: GrayCodeOptions | None = None) -> GrayScan:
    """Full bit-plane scan (columns and rows) decoded and triangulated; the gray code unless
    ``options.code`` names another.

    Frames are streamed into a :class:`GrayDecoder` as they are captured: white and black are
    rendered first, then each bit's pattern (and its inverse, by linearity or rendered) is
    rendered, sensed and decoded before the next, so memory holds a few frames plus the
    per-pixel bits, never the whole stack. Frames are sensed in OpenCV stack order (pattern,
    inverse pairs, then white and black).

    Parameters
    ----------
    capture : object with ``render`` and ``sense`` (module docstring)
    rig : Rig
    options : GrayCodeOptions, optional
        Thresholds, inverses, triangulation method, sub-pixel refinement, kept frames, code.

    Returns
    -------
    GrayScan
    """
    o, (H, W) = scan_inputs(rig, options, GrayCodeOptions)
    stack = encode(W, H, o.code)
    n_bits = len(stack) // 2
    wb_r = render_checked(
        capture, np.stack([np.ones((H, W), np.float32), np.zeros((H, W), np.float32)])
    )
    renders = 2
    dec = GrayDecoder(
        (H, W),
        wb_r.shape[1:],
        black_threshold=o.black_threshold,
        white_threshold=o.white_threshold,
        keep_diff=o.subpixel,
        code=o.code,
    )
    kept = [] if o.keep_frames else None
    for k in range(n_bits):
        if o.inverses == "linearity":
            pat_r = render_checked(capture, stack[2 * k : 2 * k + 1].astype(np.float32) / 255.0)
            pair_r = np.concatenate([pat_r, inverses_by_linearity(pat_r, wb_r[0], wb_r[1])])
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


def _bits(proj_shape) -> tuple[int, int]:
    H, W = (int(proj_shape[0]), int(proj_shape[1]))
    return num_bits(W), num_bits(H)


def _frame_names(options: GrayCodeOptions, proj_shape) -> list[str]:
    return frame_names(*_bits(proj_shape))


def _patterns(proj_shape, options: GrayCodeOptions) -> np.ndarray:
    """(2 bits, H, W) float32 in [0, 1]: :func:`encode` of the options' code."""
    H, W = (int(proj_shape[0]), int(proj_shape[1]))
    return encode(W, H, options.code).astype(np.float32) / 255


def _decode(images, white, black, *, proj_shape, options: GrayCodeOptions) -> GrayDecode:
    o = options
    return decode(
        images,
        white,
        black,
        proj_shape=proj_shape,
        black_threshold=o.black_threshold,
        white_threshold=o.white_threshold,
        require_reliable=o.require_reliable,
        code=o.code,
    )


@dataclass
class GrayCoding(WhiteBlackLastCoding):
    """A bit-plane code (the gray code unless its options name another) as a coding of
    :data:`simlunar.scanner.codings.CODINGS`."""

    options: GrayCodeOptions = field(default_factory=GrayCodeOptions)
    frame_order = "OpenCV GrayCodePattern.generate() order, then white, black"
    _fns = StackFunctions(_frame_names, _patterns, _decode, gray_code_scan)

    def export_meta(self, decode: GrayDecode) -> dict:
        o = self.options
        return {
            "code": o.code.name,
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
