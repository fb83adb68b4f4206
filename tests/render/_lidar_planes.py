"""Shared scenes of the LIDAR acquisition tests: a flat plane 50 m below a nadir sensor."""

from __future__ import annotations

import numpy as np

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar import DetectorOptions
from simlunar.terrain import Terrain

H = 50.0


# about 50 signal photons per pulse from the plane at 50 m (rendered L = 0.2 / (pi R^2))
DET = DetectorOptions(signal_photons=2e6, background_photons_per_s=0.0, pulses=4)


def _plane(size: float = 80.0) -> Terrain:
    n = int(size)
    return Terrain(
        heights=np.zeros((n, n)),
        albedo=np.full((n, n), 0.2, np.float32),
        spacing=1.0,
        origin=(-size / 2, size / 2),
    )


def _camera(px: int, fov_deg: float) -> Camera:
    pose = Pose.look_at([0.0, 0.0, H], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    return Camera(Intrinsics.from_fov(px, px, fov_deg), pose)
