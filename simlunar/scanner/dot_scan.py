"""The dot scan: given projector pixels lit as dots (one per frame, or multiplexed several per
frame by :func:`simlunar.scanner.scheduling.schedule_dots`), found in the camera along their
epipolar segments and triangulated (:mod:`simlunar.scanner.dots` detects and matches them).

The scan drives any *capture* (the :class:`~simlunar.render.capture.Capture` protocol:
``render(patterns)`` noise-free images, one render per pattern, and ``sense(images)`` captured
frames). The scanner's modes that use it (ambiguity enhancement, data reduction) are those of
the structured-light sensor, :mod:`simlunar.sensors.structured_light`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Rig
from simlunar.progress import stage
from simlunar.registry import Options, option
from simlunar.scanner import dots as _dots
from simlunar.scanner.coded import render_checked
from simlunar.scanner.scheduling import schedule_dots
from simlunar.scanner.triangulate import (
    Correspondences,
    PointCloud,
    check_rig,
    depth_at_proj_pixels,
    triangulate,
)

__all__ = ["DotOptions", "DotScan", "dot_scan"]


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
