"""The structured-light scanner of the paper's section 5 as a range sensor.

Its modes: ``gray_code`` (a full gray-code scan, no plan), ``ambiguity_enhancement`` (the gray
code, then the planned pixels rescanned with multiplexed dots, the dots replacing the gray-code
depth where they were found) and ``data_reduction`` (only the planned dots). The gray-code scan
is made once per sensor and shared by every plan (it does not depend on the plan).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simlunar.geometry import Rig
from simlunar.render.capture import Capture
from simlunar.scanner.scans import (
    DotOptions,
    DotScan,
    GrayCodeOptions,
    GrayScan,
    dot_scan,
    gray_code_scan,
)
from simlunar.sensors.base import Acquisition

__all__ = ["MODES", "ScanResult", "StructuredLight", "StructuredLightOptions"]

#: the scanner's modes; ``gray_code`` takes no plan
MODES = ("gray_code", "ambiguity_enhancement", "data_reduction")


@dataclass(frozen=True)
class StructuredLightOptions:
    """Options of :class:`StructuredLight`.

    Attributes
    ----------
    mode : one of :data:`MODES`
    gray : GrayCodeOptions
        The gray-code scan (modes ``gray_code`` and ``ambiguity_enhancement``).
    dots : DotOptions
        The dot scans of the planned pixels.
    """

    mode: str = "ambiguity_enhancement"
    gray: GrayCodeOptions = field(default_factory=GrayCodeOptions)
    dots: DotOptions = field(default_factory=DotOptions)

    def __post_init__(self):
        if self.mode not in MODES:
            raise ValueError(f"unknown scan mode {self.mode!r}; valid: {sorted(MODES)}")


@dataclass(frozen=True, eq=False)
class ScanResult:
    """What one structured-light acquisition did.

    Attributes
    ----------
    mode : str
    measured : (H, W) guide-view depth of the measured pixels only (NaN holes), m
    renders : int rendered frames of this acquisition (the shared gray code counted once, by
        the ``gray_code`` mode)
    gray : GrayScan or None
    dots : DotScan or None
    planned_rc : (k, 2) int or None guide pixels the planner chose
    """

    mode: str
    measured: np.ndarray
    renders: int
    gray: GrayScan | None = None
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
    gray : GrayScan, optional
        A gray-code scan made already (shared between the sensors of one study).
    """

    name = "structured_light"

    def __init__(
        self,
        capture: Capture,
        rig: Rig,
        *,
        depth_range: tuple[float, float],
        options: StructuredLightOptions | None = None,
        gray: GrayScan | None = None,
    ) -> None:
        self.capture = capture
        self.rig = rig
        self.depth_range = depth_range
        self.options = options or StructuredLightOptions()
        self._gray = gray

    @property
    def needs_plan(self) -> bool:
        return self.options.mode != "gray_code"

    @property
    def proj_shape(self) -> tuple[int, int]:
        return self.rig.projector.intrinsics.shape

    def gray_scan(self) -> GrayScan:
        """The gray-code scan (made on first use, then shared)."""
        if self._gray is None:
            self._gray = gray_code_scan(self.capture, self.rig, self.options.gray)
        return self._gray

    def acquire(self, rc: np.ndarray | None, *, rng=None) -> Acquisition:
        """Scan in this sensor's mode; ``rc`` (k, 2) (row, col) guide pixels for the dot modes."""
        mode = self.options.mode
        if mode == "gray_code":
            g = self.gray_scan()
            res = ScanResult(mode, g.depth, g.renders, gray=g)
            return Acquisition.from_map(g.depth, frames=g.renders, detail=res)
        if rc is None:
            raise ValueError(f"scan mode {mode!r} rescans planned pixels: rc is required")
        rc = np.asarray(rc, np.int64)
        # guide pixel (r, c) is projector pixel (r, c): its centre is (u, v) = (c + .5, r + .5)
        uv = np.c_[rc[:, 1] + 0.5, rc[:, 0] + 0.5]
        d = dot_scan(
            self.capture, self.rig, uv, depth_range=self.depth_range, options=self.options.dots
        )
        if mode == "data_reduction":
            measured, g = d.depth, None
        else:
            g = self.gray_scan()
            measured = g.depth.copy()
            hit = np.isfinite(d.depth)
            measured[hit] = d.depth[hit]
        res = ScanResult(mode, measured, d.renders, gray=g, dots=d, planned_rc=rc)
        return Acquisition.from_map(measured, frames=d.renders, detail=res)
