"""N-step phase shifting with multi-frequency temporal (hierarchical) unwrapping (NumPy only).

Patterns (one set per axis, columns then rows; per axis one level per fringe period, coarsest
first; per level ``N`` shifts)::

    P_{l,n}(u) = 1/2 + 1/2 cos(Phi_l(u) + 2 pi n / N),   Phi_l(u) = 2 pi (u + o) / p_l

with ``u`` the projector coordinate (pixel centres at ``col + 0.5``), ``p_l`` the fringe period
of level ``l`` in projector pixels (:func:`~simlunar.scanner.fringes.fringe_periods`: the finest ``period_px``, each
coarser one ``ratio`` times longer, the coarsest longer than the axis) and ``o = (p_0 - n) / 2``
the offset that centres the ``n`` pixels of the axis in the coarsest period (so its phase is
unambiguous and never wraps at the axis' ends).

Decoder (the formulas and sources of :mod:`.fringes`), per camera pixel and level, from the captured
``I_n = A + B cos(phi + 2 pi n / N)``:

* wrapped phase ``phi = atan2(-sum I_n sin(2 pi n / N), sum I_n cos(2 pi n / N))`` (unbiased
  for any ``N >= 3``: the sums project the samples on the first harmonic);
* modulation ``B = (2 / N) |sum I_n exp(-i 2 pi n / N)|``; phase noise of white frame noise
  ``sigma_I``: ``sigma_phi = sqrt(2 / N) sigma_I / B`` (:func:`~simlunar.scanner.fringes.phase_noise_std`);
* temporal unwrapping from the coarsest level up: ``Phi_0 = phi_0``,
  ``k_l = round((p_{l-1} / p_l Phi_{l-1} - phi_l) / (2 pi))``, ``Phi_l = phi_l + 2 pi k_l``;
  the position is ``u = p_L Phi_L / (2 pi) - o`` from the finest level, whose noise
  ``sigma_u = p_L sigma_phi / (2 pi)`` is the coding's positional uncertainty.

A pixel is valid if the projector lights it (``white - black > black_threshold``, as the gray
code's rule), its modulation reaches ``min_modulation`` at every level, every unwrapping step
is consistent (``|p_{l-1} / p_l Phi_{l-1} - Phi_l| <= unwrap_tolerance``) and the decoded
coordinates lie inside the projector.

With an even ``N`` the shifts ``n + N / 2`` are the inverses of the shifts ``n`` (the patterns
sum to the white frame), so by linearity of light transport they need no render:
``I(inverse) = I(white) + I(black) - I(pattern)`` (``inverses="linearity"``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simlunar.registry import option, shared_option
from simlunar.scanner._fringe import FRINGE_OPTIONS, check_fringe_options
from simlunar.scanner.coded import StackFunctions, WhiteBlackLastCoding, render_checked, scan_inputs
from simlunar.scanner.fringes import fringe_periods, unwrap, wrapped_phase
from simlunar.scanner.result import coded_scan

__all__ = [
    "PhaseDecode",
    "PhaseDecoder",
    "PhaseShiftCoding",
    "PhaseShiftOptions",
    "coord_scores",
    "decode",
    "encode",
    "frame_names",
    "phase_shift_scan",
]

_INVERSES = ("linearity", "render")


@dataclass(frozen=True)
class PhaseShiftOptions:
    """Options of the phase-shift coding (module docstring).

    ``keep_frames`` keeps the captured stack in ``CodedScan.frames["images"]`` (not a YAML
    option).
    """

    steps: int = option(4, doc="phase shifts per fringe period", ge=3, le=64)
    period_px: float = option(8.0, doc="finest fringe period", unit="px", ge=2.0)
    ratio: float = option(
        8.0,
        doc="period ratio between unwrapping levels (temporal unwrapping needs the coarser "
        "level's phase error below pi / ratio)",
        gt=1.0,
        le=64.0,
    )
    axes: str = shared_option(FRINGE_OPTIONS, "axes")
    black_threshold: float = shared_option(FRINGE_OPTIONS, "black_threshold")
    min_modulation: float = option(
        0.01, doc="smallest modulation B accepted at every level (frame units)", ge=0, le=1
    )
    unwrap_tolerance: float = option(
        1.0,
        doc="largest disagreement between a level's unwrapped phase and the coarser level's "
        "scaled phase (rad)",
        gt=0,
        le=np.pi,
    )
    inverses: str = option(
        "linearity",
        doc="with an even steps, the shifts n + N/2 by linearity of light (no render) or rendered",
        choices=_INVERSES,
    )
    method: str = shared_option(FRINGE_OPTIONS, "method")
    keep_frames: bool = False

    def __post_init__(self):
        check_fringe_options(self, whole="steps")


def _axes(options: PhaseShiftOptions, proj_shape) -> list[tuple[str, int, tuple[float, ...]]]:
    """(axis name, axis length, periods) of each coded axis: columns (width), rows (height)."""
    H, W = (int(proj_shape[0]), int(proj_shape[1]))
    names = [("col", W), ("row", H)] if options.axes == "both" else [("col", W)]
    return [(a, n, fringe_periods(n, options.period_px, options.ratio)) for a, n in names]


def _offset(n: int, periods) -> float:
    return (periods[0] - n) / 2.0


def frame_names(options: PhaseShiftOptions, proj_shape) -> list[str]:
    """Frame names in stack order: ``col<l>_s<n>`` (column level l, coarsest 0, shift n),
    then ``row<l>_s<n>``, then ``white``, ``black``."""
    names = []
    for axis, _n, periods in _axes(options, proj_shape):
        for level in range(len(periods)):
            names += [f"{axis}{level}_s{s}" for s in range(int(options.steps))]
    return [*names, "white", "black"]


def _level_patterns(n: int, periods, level: int, steps: int) -> np.ndarray:
    """(steps, n) float64 pattern values at the axis' pixel centres for one level."""
    u = np.arange(n) + 0.5
    phase = 2 * np.pi * (u + _offset(n, periods)) / periods[level]
    shifts = 2 * np.pi * np.arange(steps) / steps
    return 0.5 + 0.5 * np.cos(phase[None, :] + shifts[:, None])


def encode(proj_shape, options: PhaseShiftOptions | None = None) -> np.ndarray:
    """The phase-shift pattern stack (white and black excluded) in :func:`frame_names` order.

    Parameters
    ----------
    proj_shape : (H, W)
    options : PhaseShiftOptions, optional

    Returns
    -------
    (axes x levels x steps, H, W) float32 in [0, 1]
    """
    o = options or PhaseShiftOptions()
    H, W = (int(proj_shape[0]), int(proj_shape[1]))
    out = []
    for axis, n, periods in _axes(o, (H, W)):
        for level in range(len(periods)):
            p = _level_patterns(n, periods, level, int(o.steps)).astype(np.float32)
            if axis == "col":
                out.append(np.broadcast_to(p[:, None, :], (len(p), H, W)))
            else:
                out.append(np.broadcast_to(p[:, :, None], (len(p), H, W)))
    return np.ascontiguousarray(np.concatenate(out))


@dataclass(frozen=True, eq=False)
class PhaseDecode:
    """Dense result of decoding a phase-shift stack seen by a camera (arrays (rows, cols)).

    Attributes
    ----------
    u, v : float64
        Decoded projector coordinates (pixel centres at ``col + 0.5``), whether valid or not
        (NaN where unlit); ``v`` NaN everywhere for a columns-only coding.
    valid : bool
        Lit, modulated at every level, consistently unwrapped and inside the projector.
    lit : bool
        ``white - black > black_threshold``.
    modulation : float64
        Smallest modulation ``B`` over the levels and axes (frame units).
    disagreement : float64
        Largest unwrapping disagreement (rad).
    contrast : float32
        ``white - black``.
    proj_shape : (H, W)
    """

    u: np.ndarray
    v: np.ndarray
    valid: np.ndarray
    lit: np.ndarray
    modulation: np.ndarray
    disagreement: np.ndarray
    contrast: np.ndarray
    proj_shape: tuple[int, int]

    @property
    def shape(self) -> tuple[int, int]:
        return self.valid.shape  # type: ignore[return-value]

    def decoded_index(self) -> tuple[np.ndarray, np.ndarray]:
        """``(col, row)`` int64 projector pixel each camera pixel's phase names, valid or not
        (-1 where it names none: unlit, or no row phase)."""
        return _index(self.u), _index(self.v)

    @property
    def col(self) -> np.ndarray:
        """Decoded projector column, -1 where invalid."""
        return np.where(self.valid, _index(self.u), -1)

    @property
    def row(self) -> np.ndarray:
        """Decoded projector row, -1 where invalid or not coded."""
        return np.where(self.valid, _index(self.v), -1)

    def proj_uv(self) -> np.ndarray:
        """(rows, cols, 2) projector coordinates (u, v); NaN where invalid."""
        uv = np.stack([self.u, self.v], axis=-1)
        uv[~self.valid] = np.nan
        return uv


def _index(x: np.ndarray) -> np.ndarray:
    ok = np.isfinite(x)
    return np.where(ok, np.floor(np.where(ok, x, -1.0)), -1).astype(np.int64)


class PhaseDecoder:
    """Streaming phase-shift decoder: each level's frames are added as they are captured.

    Holds per camera pixel only each level's wrapped phase and the running minimum of the
    modulation, never the frame stack. :func:`decode` is this class fed a whole stack.

    Parameters
    ----------
    proj_shape : (H, W)
    cam_shape : (rows, cols)
    options : PhaseShiftOptions, optional
    """

    def __init__(self, proj_shape, cam_shape, options: PhaseShiftOptions | None = None):
        self.options = options or PhaseShiftOptions()
        self.proj_shape = (int(proj_shape[0]), int(proj_shape[1]))
        self.cam_shape = (int(cam_shape[0]), int(cam_shape[1]))
        self.axes = _axes(self.options, self.proj_shape)
        self._phases: dict[tuple[str, int], np.ndarray] = {}
        self.modulation = np.full(self.cam_shape, np.inf)
        self.lit: np.ndarray | None = None
        self.contrast: np.ndarray | None = None

    def levels(self) -> list[tuple[str, int]]:
        """(axis, level) of every frame set in stack order."""
        return [(a, lvl) for a, _n, periods in self.axes for lvl in range(len(periods))]

    def add_level(self, axis: str, level: int, frames) -> None:
        """Add the ``steps`` captured frames of one level of ``axis`` ("col" or "row")."""
        if (axis, level) not in self.levels():
            raise ValueError(f"no level {level} of axis {axis!r}; the stack has {self.levels()}")
        frames = np.asarray(frames)
        want = (int(self.options.steps), *self.cam_shape)
        if frames.shape != want:
            raise ValueError(f"level frames {frames.shape} must be {want} (steps, rows, cols)")
        phi, b, _ = wrapped_phase(frames)
        self._phases[(axis, level)] = phi
        np.minimum(self.modulation, b, out=self.modulation)

    def add_white_black(self, white, black) -> None:
        """Add the captured all-white and all-black frames."""
        w, b = np.asarray(white), np.asarray(black)
        if w.shape != self.cam_shape or b.shape != self.cam_shape:
            raise ValueError(
                f"white {w.shape} and black {b.shape} must match the camera {self.cam_shape}"
            )
        contrast = np.subtract(w, b, dtype=np.float64)
        self.lit = contrast > self.options.black_threshold
        self.contrast = contrast.astype(np.float32)

    def result(self) -> PhaseDecode:
        """The decode of the frames added so far (every level and white/black are needed)."""
        missing = [f"{a}{lvl}" for a, lvl in self.levels() if (a, lvl) not in self._phases]
        if missing or self.lit is None:
            what = missing + (["white/black"] if self.lit is None else [])
            raise ValueError(f"phase-shift decode is missing frames: {', '.join(what)}")
        o = self.options
        coords = {"col": np.full(self.cam_shape, np.nan), "row": np.full(self.cam_shape, np.nan)}
        worst = np.zeros(self.cam_shape)
        inside = np.ones(self.cam_shape, bool)
        for axis, n, periods in self.axes:
            phases = [self._phases[(axis, lvl)] for lvl in range(len(periods))]
            big, dis = unwrap(phases, periods)
            x = big * periods[-1] / (2 * np.pi) - _offset(n, periods)
            coords[axis] = np.where(self.lit, x, np.nan)
            worst = np.maximum(worst, dis)
            inside &= (x >= 0) & (x < n)
        valid = (
            self.lit
            & inside
            & (self.modulation >= o.min_modulation)
            & (worst <= o.unwrap_tolerance)
        )
        return PhaseDecode(
            u=coords["col"],
            v=coords["row"],
            valid=valid,
            lit=self.lit,
            modulation=self.modulation.copy(),
            disagreement=worst,
            contrast=self.contrast,
            proj_shape=self.proj_shape,
        )


def decode(images, white, black, *, proj_shape, options: PhaseShiftOptions | None = None):
    """Decode a whole phase-shift stack (:func:`encode` order) into projector coordinates.

    Parameters
    ----------
    images : (axes x levels x steps, rows, cols) array
    white, black : (rows, cols) array
    proj_shape : (H, W)
    options : PhaseShiftOptions, optional

    Returns
    -------
    PhaseDecode
    """
    o = options or PhaseShiftOptions()
    images = np.asarray(images)
    want = len(frame_names(o, proj_shape)) - 2
    if images.ndim != 3 or images.shape[0] != want:
        raise ValueError(
            f"images must be a ({want}, rows, cols) phase-shift stack for a "
            f"{proj_shape[1]}x{proj_shape[0]} projector, got shape {images.shape}"
        )
    dec = PhaseDecoder(proj_shape, images.shape[1:], o)
    N = int(o.steps)
    for i, (axis, level) in enumerate(dec.levels()):
        dec.add_level(axis, level, images[i * N : (i + 1) * N])
    dec.add_white_black(white, black)
    return dec.result()


def phase_shift_scan(capture, rig, options: PhaseShiftOptions | None = None):
    """A full phase-shift scan, decoded and triangulated.

    White and black are rendered first; then every level's shifts (with an even ``steps`` and
    ``inverses="linearity"`` only the first half: the rest are ``white + black - image``),
    each level sensed and decoded before the next. The capture protocol is that of
    :mod:`simlunar.scanner.gray_code`.

    Returns
    -------
    CodedScan
    """
    o, (H, W) = scan_inputs(rig, options, PhaseShiftOptions)
    stack = encode((H, W), o)
    N = int(o.steps)
    wb_r = render_checked(
        capture, np.stack([np.ones((H, W), np.float32), np.zeros((H, W), np.float32)])
    )
    renders = 2
    dec = PhaseDecoder((H, W), wb_r.shape[1:], o)
    by_linearity = o.inverses == "linearity" and N % 2 == 0
    kept = [] if o.keep_frames else None
    for i, (axis, level) in enumerate(dec.levels()):
        pats = stack[i * N : (i + 1) * N]
        if by_linearity:
            half = render_checked(capture, pats[: N // 2])
            imgs = np.concatenate([half, wb_r[0][None] + wb_r[1][None] - half])
            renders += N // 2
        else:
            imgs = render_checked(capture, pats)
            renders += N
        frames = np.asarray(capture.sense(imgs))
        dec.add_level(axis, level, frames)
        if kept is not None:
            kept.append(frames)
    white, black = np.asarray(capture.sense(wb_r))
    dec.add_white_black(white, black)
    result = dec.result()
    images = None if kept is None else np.concatenate(kept)
    return coded_scan(
        rig, result, white, black, images, renders=renders, coding=PhaseShiftCoding(o)
    )


@dataclass
class PhaseShiftCoding(WhiteBlackLastCoding):
    """Phase shifting as a coding of :data:`simlunar.scanner.codings.CODINGS`."""

    options: PhaseShiftOptions = field(default_factory=PhaseShiftOptions)
    frame_order = (
        "per axis (columns, then rows), per level (coarsest first), the N shifts; then white, black"
    )
    _fns = StackFunctions(frame_names, encode, decode, phase_shift_scan)

    def export_meta(self, decode: PhaseDecode) -> dict:
        o = self.options
        return {
            "steps": int(o.steps),
            "periods_px": {
                axis: list(periods) for axis, _n, periods in _axes(o, decode.proj_shape)
            },
            "phase_offsets_px": {
                axis: _offset(n, periods) for axis, n, periods in _axes(o, decode.proj_shape)
            },
            "pattern": "1/2 + 1/2 cos(2 pi (u + offset) / period + 2 pi n / steps), "
            "u = col + 0.5 (simlunar pixel centres)",
            "black_threshold": float(o.black_threshold),
            "min_modulation": float(o.min_modulation),
            "unwrap_tolerance_rad": float(o.unwrap_tolerance),
            "inverses": str(o.inverses),
            "triangulation": str(o.method),
        }

    def phase_maps(self, images, decode: PhaseDecode) -> dict[str, np.ndarray]:
        """The wrapped phase of every level (``<axis><level>_wrapped``, from the captured
        ``images`` in stack order) and the absolute phase of the finest
        (``<axis>_absolute`` = ``2 pi (u + offset) / period``, NaN where unlit), rad, float32."""
        o = self.options
        N = int(o.steps)
        maps, i = {}, 0
        for axis, n, periods in _axes(o, decode.proj_shape):
            for level in range(len(periods)):
                maps[f"{axis}{level}_wrapped"] = wrapped_phase(images[i * N : (i + 1) * N])[0]
                i += 1
            x = decode.u if axis == "col" else decode.v
            maps[f"{axis}_absolute"] = 2 * np.pi * (x + _offset(n, periods)) / periods[-1]
        return {k: np.asarray(v, np.float32) for k, v in maps.items()}

    def truth_scores(self, scan, truth: dict, mask=None) -> dict[str, float]:
        """The decoding error against the continuous truth (``truth["uv"]``: where each
        camera pixel's ray meets the projector image, not the pixel it falls in):
        ``coord_err_rate``, the fraction of valid camera pixels decoded more than one projector
        pixel off in u (or v, with rows coded): an unwrapping error; ``coord_rmse_px``, the RMS
        of decoded minus true u over the rest (projector px). Only pixels lit in the truth and
        the decode count."""
        return coord_scores(scan.decode, truth, mask, rows=self.options.axes == "both")


def coord_scores(dec, truth: dict, mask=None, *, rows: bool = True) -> dict[str, float]:
    """:meth:`PhaseShiftCoding.truth_scores` of a decode with ``u``, ``v`` (``rows``: v is
    coded and scored too)."""
    tu, tv = truth["uv"][..., 0], truth["uv"][..., 1]
    m = truth["lit"] & dec.valid & np.isfinite(tu)
    if mask is not None:
        m &= np.asarray(mask, bool)
    du = np.abs(dec.u - tu)
    bad = du > 1.0
    if rows:
        bad |= np.abs(dec.v - tv) > 1.0
    n = int(m.sum())
    if n == 0:
        return {"coord_err_rate": float("nan"), "coord_rmse_px": float("nan")}
    good = m & ~bad
    rmse = float(np.sqrt(np.mean(du[good] ** 2))) if good.any() else float("nan")
    return {"coord_err_rate": float((bad & m).sum() / n), "coord_rmse_px": rmse}
