"""Cameras, projectors, rigs and poses (NumPy only). Conventions in :mod:`.camera`."""

from simlunar.geometry.camera import (
    Camera,
    Intrinsics,
    OrthoCamera,
    Pose,
    Projector,
    Rig,
    pixel_centers,
)

__all__ = ["Camera", "Intrinsics", "OrthoCamera", "Pose", "Projector", "Rig", "pixel_centers"]
