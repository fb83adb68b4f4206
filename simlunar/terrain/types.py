"""The :class:`Terrain` grid type shared by every layer."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Terrain"]


@dataclass(frozen=True, eq=False)
class Terrain:
    """A height field with albedo on a regular grid.

    Parameters
    ----------
    heights : (rows, cols) float64 array
        Surface height z in metres; NaN marks nodata cells.
    albedo : (rows, cols) float32 array
        Normal albedo (reflectance) in [0, 1] per cell.
    spacing : float
        Cell size in metres (square cells).
    origin : (2,) tuple
        World (x, y) of the top-left (north-west) corner of cell (0, 0). Columns run to +x,
        rows to -y, so the centre of cell (r, c) is
        ``(x0 + (c + 0.5) * spacing, y0 - (r + 0.5) * spacing)``.
    crs : str, optional
        Coordinate reference system of (x, y) as WKT (e.g. read from a GeoTIFF); None for a
        local frame (written to GeoTIFF as the Moon 2015 sphere, see :mod:`simlunar.terrain.io`).
    """

    heights: np.ndarray
    albedo: np.ndarray
    spacing: float
    origin: tuple[float, float] = (0.0, 0.0)
    crs: str | None = None

    def __post_init__(self) -> None:
        h = np.array(self.heights, dtype=np.float64, copy=True)
        a = np.array(self.albedo, dtype=np.float32, copy=True)
        if h.ndim != 2:
            raise ValueError(f"heights must be 2-D (rows, cols), got shape {h.shape}")
        if a.shape != h.shape:
            raise ValueError(f"albedo shape {a.shape} does not match heights shape {h.shape}")
        if not (np.isfinite(self.spacing) and self.spacing > 0):
            raise ValueError(f"spacing must be a positive number of metres, got {self.spacing}")
        if np.any(np.isinf(h)):
            raise ValueError("heights contain inf (use NaN for nodata)")
        h.setflags(write=False)
        a.setflags(write=False)
        object.__setattr__(self, "heights", h)
        object.__setattr__(self, "albedo", a)
        object.__setattr__(self, "spacing", float(self.spacing))
        object.__setattr__(self, "origin", (float(self.origin[0]), float(self.origin[1])))
        if self.crs is not None and not isinstance(self.crs, str):
            raise ValueError(f"crs must be a WKT string or None, got {type(self.crs).__name__}")

    @property
    def shape(self) -> tuple[int, int]:
        return self.heights.shape  # type: ignore[return-value]

    @property
    def nodata(self) -> np.ndarray:
        """Boolean mask of nodata cells."""
        return np.isnan(self.heights)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax) of the grid's outer cell edges in metres."""
        rows, cols = self.shape
        x0, y0 = self.origin
        return (x0, x0 + cols * self.spacing, y0 - rows * self.spacing, y0)

    def cell_centers(self) -> tuple[np.ndarray, np.ndarray]:
        """World x (cols,) and y (rows,) of cell centres."""
        rows, cols = self.shape
        x = self.origin[0] + (np.arange(cols) + 0.5) * self.spacing
        y = self.origin[1] - (np.arange(rows) + 0.5) * self.spacing
        return x, y

    def points(self) -> np.ndarray:
        """(rows, cols, 3) world positions of cell centres."""
        x, y = self.cell_centers()
        X, Y = np.meshgrid(x, y)
        return np.stack([X, Y, self.heights], axis=-1)
