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
from simlunar.geometry.emitters import beam_intensity, beam_profile, point_irradiance

__all__ = [
    "Camera",
    "Intrinsics",
    "OrthoCamera",
    "Pose",
    "Projector",
    "Rig",
    "beam_intensity",
    "beam_profile",
    "grid_height_at",
    "pixel_centers",
    "point_irradiance",
    "rover_mast_camera",
]
