"""Procedural lunar terrain and DEM I/O (NumPy/SciPy only)."""

from simlunar.terrain.types import Terrain

__all__ = ["Terrain"]
