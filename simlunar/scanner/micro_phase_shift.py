"""Micro phase shifting (Gupta & Nayar, CVPR 2012, "Micro Phase Shifting"; NumPy only).

All fringes lie in one narrow band of high frequencies, so every pattern is blurred (by
defocus, subsurface scattering) and spread by interreflections about equally: the property
that makes the coding robust where the coarse levels of temporal unwrapping fail
(Gupta, Agrawal, Veeraraghavan & Narasimhan, CVPR 2011: low frequencies suffer from
interreflections).

Per axis ``F + 2`` patterns (columns, then rows, then white and black)::

    P_{0,s}(u) = 1/2 + 1/2 cos(2 pi f_0 u + 2 pi s / 3),   s = 0, 1, 2
    P_j(u)     = 1/2 + 1/2 cos(2 pi f_j u),                  j = 1 ... F - 1

with ``u`` the projector coordinate (pixel centres at ``col + 0.5``) and the frequencies
``f_j`` spread evenly over ``(1 +- band / 2) / period_px`` (:func:`frequencies`). Decoding, per
camera pixel, after the paper: the three shifts of ``f_0`` give the offset ``O``, the amplitude
``A`` and the wrapped phase ``phi_0`` (the N-step formulas of
:mod:`simlunar.scanner.phase_shift`); each other frame gives ``cos phi_j = (I_j - O) / A``. The
wrapped ``phi_0`` places the point exactly within a period of ``f_0``; of its positions in the
periods along the axis, the decoder keeps the one whose ``cos(2 pi f_j u)`` are closest to the
measured ``cos phi_j`` (least squares; the search of the paper, over periods instead of
pixels, so the coordinate stays sub-pixel). Evenly spaced frequencies
``Delta`` apart make the phase vector repeat about every ``1 / Delta = (F - 1) period_px /
band`` pixels (:func:`unambiguous_px`; 640 px for the defaults): a longer axis is refused (more
frequencies or a narrower band; Gupta & Nayar choose uneven frequencies to stretch it).

A pixel is valid if lit (``white - black > black_threshold``), modulated (``A >=
min_modulation``), its closest phase vector is close (RMS mismatch ``<= max_mismatch``), the
coordinate lies inside the projector.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simlunar.registry import option, shared_option
from simlunar.scanner._fringe import FRINGE_OPTIONS, check_fringe_options
from simlunar.scanner.coded import StackFunctions, WhiteBlackLastCoding, scan_inputs
from simlunar.scanner.fringes import wrapped_phase
from simlunar.scanner.phase_shift import PhaseDecode, coord_scores
from simlunar.scanner.result import coded_scan

__all__ = [
    "MicroPhaseShiftCoding",
    "MicroPhaseShiftOptions",
    "decode",
    "encode",
    "frame_names",
    "frequencies",
    "micro_phase_shift_scan",
    "unambiguous_px",
]

#: camera pixels searched at once (bounds the (pixels, periods) mismatch array)
_CHUNK = 4096


@dataclass(frozen=True)
class MicroPhaseShiftOptions:
    """Options of the micro phase-shift coding (module docstring).

    ``keep_frames`` keeps the captured stack (not a YAML option).
    """

    period_px: float = option(16.0, doc="mean fringe period", unit="px", ge=2.0)
    band: float = option(
        0.1,
        doc="relative width of the frequency band (Gupta & Nayar keep it narrow, about 10 %)",
        gt=0.0,
        le=0.5,
    )
    frequencies: int = option(
        5, doc="number of fringe frequencies F (F + 2 patterns per axis)", ge=2, le=32
    )
    axes: str = shared_option(FRINGE_OPTIONS, "axes")
    black_threshold: float = shared_option(FRINGE_OPTIONS, "black_threshold")
    min_modulation: float = option(0.01, doc="smallest amplitude A (frame units)", ge=0, le=1)
    max_mismatch: float = option(
        0.1,
        doc="largest RMS difference between the measured phase vector and the closest pixel's",
        gt=0,
        le=2,
    )
    method: str = shared_option(FRINGE_OPTIONS, "method")
    keep_frames: bool = False

    def __post_init__(self):
        check_fringe_options(self, whole="frequencies")


def frequencies(options: MicroPhaseShiftOptions) -> np.ndarray:
    """(F,) fringe frequencies (cycles per projector pixel), evenly over the band; the first
    is the one shifted three times."""
    o = options
    rel = np.linspace(-0.5, 0.5, int(o.frequencies)) * o.band
    return (1.0 + rel) / o.period_px


def unambiguous_px(options: MicroPhaseShiftOptions) -> float:
    """Length (projector px) over which the phase vector of evenly spaced frequencies does not
    repeat: ``1 / Delta = (F - 1) period_px / band``."""
    return (int(options.frequencies) - 1) * options.period_px / options.band


def _axes(o: MicroPhaseShiftOptions, proj_shape) -> list[tuple[str, int]]:
    H, W = (int(proj_shape[0]), int(proj_shape[1]))
    return [("col", W), ("row", H)] if o.axes == "both" else [("col", W)]


def _check_length(o: MicroPhaseShiftOptions, proj_shape) -> None:
    longest = max(n for _a, n in _axes(o, proj_shape))
    if longest > unambiguous_px(o):
        raise ValueError(
            f"micro phase shift with {o.frequencies} frequencies over a band of {o.band:g} at "
            f"{o.period_px:g} px repeats every {unambiguous_px(o):.0f} px, shorter than the "
            f"{longest}-px projector axis: use more frequencies or a narrower band"
        )


def frame_names(options: MicroPhaseShiftOptions, proj_shape) -> list[str]:
    """``col_f0_s0..2``, ``col_f1`` ... ``col_f<F-1>``, the same for rows, ``white``,
    ``black``."""
    _check_length(options, proj_shape)  # a stack that repeats has no names to give
    F = int(options.frequencies)
    names = []
    for axis, _n in _axes(options, proj_shape):
        names += [f"{axis}_f0_s{s}" for s in range(3)] + [f"{axis}_f{j}" for j in range(1, F)]
    return [*names, "white", "black"]


def _axis_patterns(n: int, o: MicroPhaseShiftOptions) -> np.ndarray:
    """(F + 2, n) pattern values at the axis' pixel centres."""
    u = np.arange(n) + 0.5
    f = frequencies(o)
    rows = [0.5 + 0.5 * np.cos(2 * np.pi * f[0] * u + 2 * np.pi * s / 3) for s in range(3)]
    rows += [0.5 + 0.5 * np.cos(2 * np.pi * fj * u) for fj in f[1:]]
    return np.stack(rows)


def encode(proj_shape, options: MicroPhaseShiftOptions | None = None) -> np.ndarray:
    """The pattern stack (white and black excluded), (axes x (F + 2), H, W) float32 in [0, 1]."""
    o = options or MicroPhaseShiftOptions()
    H, W = (int(proj_shape[0]), int(proj_shape[1]))
    _check_length(o, (H, W))
    out = []
    for axis, n in _axes(o, (H, W)):
        p = _axis_patterns(n, o).astype(np.float32)
        out.append(
            np.broadcast_to(p[:, None, :] if axis == "col" else p[:, :, None], (len(p), H, W))
        )
    return np.ascontiguousarray(np.concatenate(out))


def _decode_axis(frames: np.ndarray, n: int, o: MicroPhaseShiftOptions):
    """Coordinate, amplitude and mismatch of one axis from its F + 2 frames (pixels flat).

    ``phi_0`` fixes the position inside a period of ``f_0`` exactly; the candidates are its
    positions in every period along the axis, and the one whose ``cos(2 pi f_j u)`` match the
    measured ``cos phi_j`` best (least squares) wins.
    """
    f = frequencies(o)
    phi0, amp, offset = wrapped_phase(frames[:3])
    safe = np.maximum(amp, 1e-12)
    meas = (frames[3:] - offset[None]) / safe[None]  # (F - 1, pixels) measured cos phi_j
    k = np.arange(int(np.ceil(n * f[0])) + 1)
    x = np.empty(meas.shape[1])
    cost = np.empty(meas.shape[1])
    for start in range(0, meas.shape[1], _CHUNK):
        sl = slice(start, start + _CHUNK)
        cand = (phi0[sl, None] / (2 * np.pi) + k[None]) / f[0]  # (pixels, K)
        d = np.zeros(cand.shape)
        for j, fj in enumerate(f[1:]):
            d += (np.cos(2 * np.pi * fj * cand) - meas[j, sl, None]) ** 2
        d[(cand < 0) | (cand >= n)] = np.inf
        best = np.argmin(d, axis=1)
        rows = np.arange(len(best))
        x[sl] = cand[rows, best]
        cost[sl] = d[rows, best]
    rms = np.sqrt(cost / meas.shape[0])
    return x, amp, rms, np.isfinite(rms)


def decode(images, white, black, *, proj_shape, options: MicroPhaseShiftOptions | None = None):
    """Decode a micro phase-shift stack (:func:`encode` order) into projector coordinates.

    Returns
    -------
    simlunar.scanner.phase_shift.PhaseDecode
        ``modulation`` is the amplitude ``A`` (smallest over the axes), ``disagreement`` the
        RMS phase-vector mismatch (largest over the axes).
    """
    o = options or MicroPhaseShiftOptions()
    _check_length(o, proj_shape)
    images = np.asarray(images, np.float64)
    white, black = np.asarray(white), np.asarray(black)
    per = int(o.frequencies) + 2
    axes = _axes(o, proj_shape)
    if images.ndim != 3 or images.shape[0] != per * len(axes):
        raise ValueError(
            f"images must be a ({per * len(axes)}, rows, cols) micro phase-shift stack, got "
            f"shape {images.shape}"
        )
    cam = images.shape[1:]
    if white.shape != cam or black.shape != cam:
        raise ValueError(f"white {white.shape} and black {black.shape} must match {cam}")
    contrast = np.subtract(white, black, dtype=np.float64)
    lit = contrast > o.black_threshold
    coords = {"col": np.full(cam, np.nan), "row": np.full(cam, np.nan)}
    modulation = np.full(cam, np.inf)
    mismatch = np.zeros(cam)
    ok = lit.copy()
    for i, (axis, n) in enumerate(axes):
        frames = images[i * per : (i + 1) * per].reshape(per, -1)
        x, amp, rms, good = _decode_axis(frames, n, o)
        coords[axis] = np.where(lit, x.reshape(cam), np.nan)
        modulation = np.minimum(modulation, amp.reshape(cam))
        mismatch = np.maximum(mismatch, rms.reshape(cam))
        ok &= good.reshape(cam)
    valid = ok & (modulation >= o.min_modulation) & (mismatch <= o.max_mismatch)
    return PhaseDecode(
        u=coords["col"],
        v=coords["row"],
        valid=valid,
        lit=lit,
        modulation=modulation,
        disagreement=mismatch,
        contrast=contrast.astype(np.float32),
        proj_shape=(int(proj_shape[0]), int(proj_shape[1])),
    )


def micro_phase_shift_scan(capture, rig, options: MicroPhaseShiftOptions | None = None):
    """A full micro phase-shift scan (every pattern rendered), decoded and triangulated.

    Returns
    -------
    CodedScan
    """
    o, (H, W) = scan_inputs(rig, options, MicroPhaseShiftOptions)
    stack = encode((H, W), o)
    wb = np.stack([np.ones((H, W), np.float32), np.zeros((H, W), np.float32)])
    imgs = np.asarray(capture.render(np.concatenate([stack, wb])))
    if imgs.shape[0] != len(stack) + 2:
        raise ValueError(f"capture.render returned shape {imgs.shape} for {len(stack) + 2}")
    frames = np.asarray(capture.sense(imgs))
    result = decode(frames[:-2], frames[-2], frames[-1], proj_shape=(H, W), options=o)
    images = frames[:-2] if o.keep_frames else None
    coding = MicroPhaseShiftCoding(o)
    return coded_scan(
        rig, result, frames[-2], frames[-1], images, renders=len(stack) + 2, coding=coding
    )


@dataclass
class MicroPhaseShiftCoding(WhiteBlackLastCoding):
    """Micro phase shifting as a coding of :data:`simlunar.scanner.codings.CODINGS`."""

    options: MicroPhaseShiftOptions = field(default_factory=MicroPhaseShiftOptions)
    frame_order = "per axis (columns, then rows): f0 at 3 shifts, f1 ... f(F-1); white, black"
    _fns = StackFunctions(frame_names, encode, decode, micro_phase_shift_scan)

    def export_meta(self, decode: PhaseDecode) -> dict:
        o = self.options
        return {
            "frequencies_per_px": [float(f) for f in frequencies(o)],
            "pattern": "1/2 + 1/2 cos(2 pi f u + shift), u = col + 0.5; f0 at shifts "
            "0, 2 pi/3, 4 pi/3, the others at 0",
            "black_threshold": float(o.black_threshold),
            "min_modulation": float(o.min_modulation),
            "max_mismatch": float(o.max_mismatch),
            "triangulation": str(o.method),
        }

    def phase_maps(self, images, decode: PhaseDecode) -> dict[str, np.ndarray]:
        """The wrapped phase of the shifted frequency f0 (``<axis>_f0_wrapped``, from the
        three shifted frames) and its absolute phase ``2 pi f0 u`` (``<axis>_absolute``),
        rad, float32."""
        o = self.options
        f0 = frequencies(o)[0]
        per = int(o.frequencies) + 2
        maps = {}
        for i, (axis, _n) in enumerate(_axes(o, decode.proj_shape)):
            maps[f"{axis}_f0_wrapped"] = wrapped_phase(images[i * per : i * per + 3])[0]
            x = decode.u if axis == "col" else decode.v
            maps[f"{axis}_absolute"] = 2 * np.pi * f0 * x
        return {k: np.asarray(v, np.float32) for k, v in maps.items()}

    def truth_scores(self, scan, truth: dict, mask=None) -> dict[str, float]:
        """As the phase shift's: ``coord_err_rate`` and ``coord_rmse_px``."""
        return coord_scores(scan.decode, truth, mask, rows=self.options.axes == "both")
