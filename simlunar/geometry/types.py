"""Central NumPy types shared across layers."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GroundTruth"]


@dataclass(frozen=True, eq=False)
class GroundTruth:
    """Per-pixel ground truth for one rendered view (arrays are (rows, cols[, 3])).

    Parameters
    ----------
    depth : float64
        z-depth along the optical axis in metres (orthographic: distance from the image plane
        along the view direction). NaN where ``valid`` is False.
    position : float64, (..., 3)
        World position of the surface seen by the pixel centre (m). NaN where invalid.
    normal : float32, (..., 3)
        World-space unit shading normal. NaN where invalid.
    valid : bool
        The pixel centre's ray hit the terrain.
    """

    depth: np.ndarray
    position: np.ndarray
    normal: np.ndarray
    valid: np.ndarray

    def __post_init__(self) -> None:
        for name in ("depth", "position", "normal", "valid"):
            arr = np.asarray(getattr(self, name))
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        if self.position.shape != (*self.depth.shape, 3) or self.valid.shape != self.depth.shape:
            raise ValueError("GroundTruth arrays must share one (rows, cols) shape")

    @property
    def shape(self) -> tuple[int, int]:
        return self.depth.shape  # type: ignore[return-value]

    @property
    def heights(self) -> np.ndarray:
        """World z of the surface seen by each pixel (m)."""
        return self.position[..., 2]
