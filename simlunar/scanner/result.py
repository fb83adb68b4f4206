"""The result of a full-field coded scan (:class:`CodedScan`) and how every coded scan ends:
triangulating its decode and bundling it with the sensed frames (:func:`coded_scan`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simlunar.geometry import Rig
from simlunar.scanner.triangulate import (
    Correspondences,
    PointCloud,
    depth_at_proj_pixels,
    triangulate,
)

__all__ = ["CodedScan", "coded_scan", "triangulated"]


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
