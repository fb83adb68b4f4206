"""The sample plan: which pixels of the native grid get a range sample."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SamplePlan"]


@dataclass(frozen=True, eq=False)
class SamplePlan:
    """k distinct in-bounds pixels of a (rows, cols) grid.

    Attributes
    ----------
    rows, cols : ndarray of int64, shape (k,)
        Pixel indices (read-only).
    shape : tuple of int
        Grid shape (rows, cols).
    """

    rows: np.ndarray
    cols: np.ndarray
    shape: tuple[int, int]

    def __post_init__(self):
        shape = tuple(int(s) for s in self.shape)
        if len(shape) != 2 or min(shape) < 1:
            raise ValueError(f"SamplePlan shape must be (rows, cols) > 0, got {self.shape!r}")
        rows = np.array(self.rows, dtype=np.int64).reshape(-1)
        cols = np.array(self.cols, dtype=np.int64).reshape(-1)
        if rows.shape != cols.shape:
            raise ValueError(
                f"SamplePlan rows and cols differ in length: {rows.size} vs {cols.size}"
            )
        if rows.size and (
            rows.min() < 0 or cols.min() < 0 or rows.max() >= shape[0] or cols.max() >= shape[1]
        ):
            raise ValueError(f"SamplePlan has pixels outside the grid {shape}")
        seen = np.zeros(shape[0] * shape[1], dtype=bool)
        seen[rows * shape[1] + cols] = True
        if np.count_nonzero(seen) != rows.size:
            raise ValueError("SamplePlan pixels must be distinct")
        rows.flags.writeable = False
        cols.flags.writeable = False
        object.__setattr__(self, "rows", rows)
        object.__setattr__(self, "cols", cols)
        object.__setattr__(self, "shape", shape)

    @classmethod
    def from_flat(cls, flat, shape) -> SamplePlan:
        """Plan from flat (row-major) pixel indices."""
        flat = np.asarray(flat, dtype=np.int64)
        return cls(flat // int(shape[1]), flat % int(shape[1]), shape)

    @property
    def k(self) -> int:
        """Number of samples."""
        return int(self.rows.size)

    @property
    def flat(self) -> np.ndarray:
        """Row-major flat indices, int64 (k,)."""
        return self.rows * self.shape[1] + self.cols

    @property
    def rc(self) -> np.ndarray:
        """(row, col) pairs, int64 (k, 2): the index coordinates ``reconstruct`` takes."""
        return np.column_stack((self.rows, self.cols))

    def mask(self) -> np.ndarray:
        """Boolean (rows, cols) image, True at the sampled pixels."""
        m = np.zeros(self.shape, dtype=bool)
        m[self.rows, self.cols] = True
        return m

    def __len__(self) -> int:
        return self.k
