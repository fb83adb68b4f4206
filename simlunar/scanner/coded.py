"""What the coded structured-light scans share: input checks, the checked render, and the
coding base classes (:data:`simlunar.scanner.codings.CODINGS` entries)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import ClassVar, NamedTuple

import numpy as np

from simlunar.geometry import Rig
from simlunar.scanner.triangulate import check_rig

__all__ = [
    "FullFieldCoding",
    "StackFunctions",
    "WhiteBlackLastCoding",
    "render_checked",
    "scan_inputs",
]


def scan_inputs(rig: Rig, options, options_cls) -> tuple[object, tuple[int, int]]:
    """Check ``rig`` (:func:`~simlunar.scanner.triangulate.check_rig`) and return the scan's
    options (``options``, or ``options_cls()`` when None) and the projector's (H, W)."""
    check_rig(rig)
    return options or options_cls(), rig.projector.intrinsics.shape


def render_checked(capture, patterns: np.ndarray) -> np.ndarray:
    """``capture.render(patterns)`` as (n, H, W) float32 / float64, one image per pattern.

    Raises
    ------
    ValueError
        The capture returned another number of images or not a stack.
    """
    imgs = np.asarray(capture.render(patterns))
    if imgs.ndim != 3 or imgs.shape[0] != len(patterns):
        raise ValueError(f"capture.render returned shape {imgs.shape} for {len(patterns)} patterns")
    if imgs.dtype not in (np.float32, np.float64):
        imgs = imgs.astype(np.float64)
    return imgs


class FullFieldCoding:
    """What the full-field codings share: ``options`` (with ``method`` and ``keep_frames``) and
    a scan function, the class attribute ``_scan(capture, rig, options) -> CodedScan``."""

    full_field = True

    @property
    def method(self) -> str:
        return self.options.method

    def scan(self, capture, rig: Rig, *, keep_frames: bool = False) -> object:
        """The scan function with these options (``keep_frames`` or the options')."""
        o = self.options
        if keep_frames and not o.keep_frames:
            o = dataclasses.replace(o, keep_frames=True)
        return self._scan(capture, rig, o)


class StackFunctions(NamedTuple):
    """The module functions of a coding whose stack is its patterns then white and black."""

    names: Callable  # (options, proj_shape) -> list of frame names
    encode: Callable  # ((H, W), options) -> (n, H, W) float32 in [0, 1]
    decode: Callable  # (images, white, black, *, proj_shape, options) -> decode
    scan: Callable  # (capture, rig, options) -> object


class WhiteBlackLastCoding(FullFieldCoding):
    """A full-field coding whose stack is its own patterns then white and black; the class
    attribute ``_fns`` (:class:`StackFunctions`) names its module's functions."""

    _fns: ClassVar[StackFunctions]

    def _scan(self, capture, rig, options) -> object:
        return self._fns.scan(capture, rig, options)

    def frames(self, proj_shape) -> int:
        return len(self.frame_names(proj_shape))

    def frame_names(self, proj_shape) -> list[str]:
        return self._fns.names(self.options, proj_shape)

    def patterns(self, proj_shape) -> np.ndarray:
        """(frames, H, W) float32: the coding's patterns, then white (ones) and black (zeros)."""
        H, W = (int(proj_shape[0]), int(proj_shape[1]))
        wb = np.stack([np.ones((H, W), np.float32), np.zeros((H, W), np.float32)])
        return np.concatenate([self._fns.encode((H, W), self.options), wb])

    def decode(self, frames, proj_shape):
        """Decode a whole stack in :meth:`patterns` order (white and black last)."""
        frames = np.asarray(frames)
        return self._fns.decode(
            frames[:-2], frames[-2], frames[-1], proj_shape=proj_shape, options=self.options
        )
