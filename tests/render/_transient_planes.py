"""Shared scenes of the time-of-flight tests: a plane at a known range below a nadir sensor."""

from __future__ import annotations

import numpy as np

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar import PulseOptions, extract_ranges
from simlunar.terrain import Terrain

H = 50.0  # sensor height above the plane (m)
IMPULSE = PulseOptions(fwhm_s=0.0)


def _read(hist, bins):
    """Noise-free ranges of rendered histograms scaled to 1000 photons each."""
    h = np.asarray(hist, float)
    return extract_ranges(1000 * h / h.sum(-1, keepdims=True), bins, pulse=IMPULSE)


def _plane(slope: float = 0.0, size: float = 60.0, spacing: float = 1.0, albedo: float = 0.2):
    n = int(size / spacing)
    x = -size / 2 + (np.arange(n) + 0.5) * spacing
    heights = np.broadcast_to(x[None, :] * slope, (n, n)).copy()
    return Terrain(
        heights=heights,
        albedo=np.full((n, n), albedo, np.float32),
        spacing=spacing,
        origin=(-size / 2, size / 2),
    )


def _nadir_camera(px: int = 16, fov_deg: float = 30.0) -> Camera:
    pose = Pose.look_at([0.0, 0.0, H], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    return Camera(Intrinsics.from_fov(px, px, fov_deg), pose)
