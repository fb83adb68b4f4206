"""The range-sensor interface: a configured object that measures range at the pixels a planner
chose and says what the measurement cost.

A sensor is built once per scene (its truth, its capture) with a small frozen options object
beside its module, and answers :meth:`Sensor.acquire` for every plan of a study. The study
protocol (:mod:`simlunar.study.protocol`) does the rest: planner -> sensor -> reconstruction ->
metrics, written once for every sensor.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from simlunar.errors import NothingMeasuredError

__all__ = ["Acquisition", "NothingMeasured", "Sensor"]


#: an acquisition measured no pixel at all: nothing to reconstruct from (a ValueError and a
#: user-facing SimlunarError: one line, exit 2)
NothingMeasured = NothingMeasuredError


@dataclass(frozen=True, eq=False)
class Acquisition:
    """Range samples of one acquisition and their cost.

    Attributes
    ----------
    rc : ndarray, shape (m, 2)
        (row, col) index coordinates of the measured cells in the guide view (cell (r, c) at
        (r, c), as :func:`simlunar.reconstruction.reconstruct` takes them).
    values : ndarray, shape (m,)
        The measured depth (m) at ``rc``.
    shape : tuple of int
        (rows, cols) of the guide view.
    frames : int
        Frames the sensor captured (renders of a scanner; 0 for the ideal sampler).
    seconds : float
        Acquisition time in seconds where the sensor models it (0 where it does not).
    energy_j : float
        Laser energy fired (J) where the sensor models it (0 where it does not).
    detail : object
        The sensor's own record of the acquisition (e.g. a structured-light ``ScanResult``).
    planned : ndarray, shape (n, 2), or None
        Every planned (row, col) in the sensor's own sample order, measured or not, where the
        sensor keeps it (a LIDAR that aims at planned pixels); ``rc`` holds those measured.
    """

    rc: np.ndarray
    values: np.ndarray
    shape: tuple[int, int]
    frames: int = 0
    seconds: float = 0.0
    detail: Any = None
    planned: np.ndarray | None = None
    energy_j: float = 0.0

    @classmethod
    def from_map(cls, measured: np.ndarray, **kw) -> Acquisition:
        """The finite cells of a guide-view depth map with NaN holes (row-major order).

        Raises
        ------
        NothingMeasured
            No finite cell.
        """
        r, c = np.nonzero(np.isfinite(measured))
        if len(r) == 0:
            raise NothingMeasured(
                "the scan measured no pixel (nothing decoded: projector too faint against the "
                "sun or the thresholds, or the camera sees no projected pixel), so there is no "
                "depth to reconstruct"
            )
        rc = np.stack([r, c], axis=-1).astype(float)
        return cls(rc, measured[r, c], tuple(measured.shape), **kw)

    def measured_map(self) -> np.ndarray:
        """(rows, cols) float64 depth at the measured cells, NaN elsewhere."""
        out = np.full(self.shape, np.nan)
        rc = np.asarray(self.rc).astype(np.int64)
        out[rc[:, 0], rc[:, 1]] = self.values
        return out


class Sensor(Protocol):
    """A configured range sensor bound to one scene.

    ``acquire(rc, rng=...)`` measures the guide pixels ``rc`` ((k, 2) int (row, col); None for
    a sensor whose acquisition needs no plan, such as a full gray-code scan) and returns an
    :class:`Acquisition`. ``needs_plan`` says whether a planner must supply ``rc``.
    """

    name: str
    needs_plan: bool

    def acquire(self, rc: np.ndarray | None, *, rng=None) -> Acquisition: ...
