"""The structured-light scanner of the paper's section 5 as a range sensor.

Its modes: every full-field coding of :data:`simlunar.scanner.codings.CODINGS` by its name (a
full scan with that coding, no plan: the gray code of the paper, phase shifting, ...),
``ambiguity_enhancement`` (the options' full-field coding, then the planned pixels rescanned
with multiplexed dots, the dots replacing the coded depth where they were found) and
``data_reduction`` (only the planned dots). The coded scan is made once per sensor and shared
by every plan (it does not depend on the plan).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from simlunar.geometry import Rig
from simlunar.render.capture import Capture
from simlunar.scanner.codings import CODINGS, DEFAULT_CODING, full_field_codings, make_coding
from simlunar.scanner.dot_scan import DotOptions, DotScan, dot_scan
from simlunar.scanner.result import CodedScan
from simlunar.sensors.base import Acquisition

__all__ = [
    "DOT_MODES",
    "MODES",
    "ScanResult",
    "StructuredLight",
    "StructuredLightOptions",
    "mode_coding",
]

#: modes that rescan planned pixels with dots (the others are the full-field codings)
DOT_MODES = ("ambiguity_enhancement", "data_reduction")

#: the scanner's modes: each full-field coding (no plan), then the dot modes
MODES = (*full_field_codings(), *DOT_MODES)


def mode_coding(mode: str, coding: str = DEFAULT_CODING) -> str | None:
    """The full-field coding a scan ``mode`` projects: the mode itself when it names a coding,
    ``coding`` for ambiguity enhancement, None for data reduction (dots only)."""
    if mode not in MODES:
        raise ValueError(f"unknown scan mode {mode!r}; valid: {sorted(MODES)}")
    if mode in CODINGS:
        return mode
    return coding if mode == "ambiguity_enhancement" else None


@dataclass(frozen=True)
class StructuredLightOptions:
    """Options of :class:`StructuredLight`.

    Attributes
    ----------
    mode : one of :data:`MODES`
    coding : str
        The full-field coding ambiguity enhancement rescans (a mode naming a coding scans
        with that one).
    codings : mapping coding name -> its options object (codings not named: defaults)
    dots : DotOptions
        The dot scans of the planned pixels.
    keep_frames : bool
        Keep the coded scan's captured stack (for the scan export).
    """

    mode: str = "ambiguity_enhancement"
    coding: str = DEFAULT_CODING
    codings: Mapping = field(default_factory=dict)
    dots: DotOptions = field(default_factory=DotOptions)
    keep_frames: bool = False

    def __post_init__(self):
        if self.mode not in MODES:
            raise ValueError(f"unknown scan mode {self.mode!r}; valid: {sorted(MODES)}")
        if self.coding not in full_field_codings():
            raise ValueError(
                f"unknown full-field coding {self.coding!r}; valid: {list(full_field_codings())}"
            )
        for name, opts in self.codings.items():
            if not isinstance(opts, CODINGS[name].options):
                raise TypeError(
                    f"codings[{name!r}] must be {CODINGS[name].options.__name__}, "
                    f"got {type(opts).__name__}"
                )

    @property
    def scanned_coding(self) -> str | None:
        """The full-field coding this mode projects (:func:`mode_coding`)."""
        return mode_coding(self.mode, self.coding)


@dataclass(frozen=True, eq=False)
class ScanResult:
    """What one structured-light acquisition did.

    Attributes
    ----------
    mode : str
    measured : (H, W) guide-view depth of the measured pixels only (NaN holes), m
    renders : int rendered frames of this acquisition (the shared coded scan counted once, by
        the mode that names its coding)
    coded : CodedScan or None
        The full-field scan (any coding; ``coded.coding`` says which).
    dots : DotScan or None
    planned_rc : (k, 2) int or None guide pixels the planner chose
    """

    mode: str
    measured: np.ndarray
    renders: int
    coded: CodedScan | None = None
    dots: DotScan | None = None
    planned_rc: np.ndarray | None = None


class StructuredLight:
    """A projector-camera rig scanning through a capture, in one mode.

    Parameters
    ----------
    capture : Capture
        Renders and senses projector patterns (:class:`simlunar.render.capture.RenderCapture`).
    rig : Rig
        Guide pixel (r, c) is projector pixel (r, c).
    depth_range : (near, far)
        Projector z-depths bounding the scene (m): the epipolar segments of the dot scans.
    options : StructuredLightOptions, optional
    coded : CodedScan, optional
        A scan with the mode's coding made already (shared between the sensors of one study).
    """

    name = "structured_light"

    def __init__(
        self,
        capture: Capture,
        rig: Rig,
        *,
        depth_range: tuple[float, float],
        options: StructuredLightOptions | None = None,
        coded: CodedScan | None = None,
    ) -> None:
        self.capture = capture
        self.rig = rig
        self.depth_range = depth_range
        self.options = options or StructuredLightOptions()
        self._coded = coded

    @property
    def needs_plan(self) -> bool:
        return self.options.mode in DOT_MODES

    @property
    def proj_shape(self) -> tuple[int, int]:
        return self.rig.projector.intrinsics.shape

    @property
    def coding(self):
        """The coding object of the full-field scan this mode makes (None: dots only)."""
        name = self.options.scanned_coding
        return None if name is None else make_coding(name, self.options.codings.get(name))

    def coded_scan(self) -> CodedScan:
        """The full-field coded scan (made on first use, then shared)."""
        if self._coded is None:
            coding = self.coding
            if coding is None:
                raise ValueError(f"scan mode {self.options.mode!r} makes no full-field scan")
            self._coded = coding.scan(self.capture, self.rig, keep_frames=self.options.keep_frames)
        return self._coded

    def acquire(self, rc: np.ndarray | None, *, rng=None) -> Acquisition:
        """Scan in this sensor's mode; ``rc`` (k, 2) (row, col) guide pixels for the dot modes."""
        mode = self.options.mode
        if not self.needs_plan:
            g = self.coded_scan()
            res = ScanResult(mode, g.depth, g.renders, coded=g)
            return Acquisition.from_map(g.depth, frames=g.renders, detail=res)
        if rc is None:
            raise ValueError(f"scan mode {mode!r} rescans planned pixels: rc is required")
        rc = np.asarray(rc, np.int64)
        # guide pixel (r, c) is projector pixel (r, c): its centre is (u, v) = (c + .5, r + .5)
        uv = np.c_[rc[:, 1] + 0.5, rc[:, 0] + 0.5]
        d = dot_scan(
            self.capture, self.rig, uv, depth_range=self.depth_range, options=self.options.dots
        )
        if self.options.scanned_coding is None:
            measured, g = d.depth, None
        else:
            g = self.coded_scan()
            measured = g.depth.copy()
            hit = np.isfinite(d.depth)
            measured[hit] = d.depth[hit]
        res = ScanResult(mode, measured, d.renders, coded=g, dots=d, planned_rc=rc)
        return Acquisition.from_map(measured, frames=d.renders, detail=res)
