"""Cameras, projectors, rigs and poses (NumPy only). Conventions in :mod:`.camera`."""

from simlunar.geometry.camera import (
    Camera,
    Intrinsics,
    OrthoCamera,
    Pose,
    Projector,
    Rig,
    grid_height_at,
    pixel_centers,
    rover_mast_camera,
)

__all__ = [
    "Camera",
    "Intrinsics",
    "OrthoCamera",
    "Pose",
    "Projector",
    "Rig",
    "grid_height_at",
    "pixel_centers",
    "rover_mast_camera",
]
