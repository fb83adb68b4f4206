"""Reconstruction of a full grid from scattered samples (Delaunay + linear interpolation)."""

from simlunar.reconstruction.delaunay import OUTSIDE_POLICIES, reconstruct, triangulate

__all__ = ["OUTSIDE_POLICIES", "reconstruct", "triangulate"]
