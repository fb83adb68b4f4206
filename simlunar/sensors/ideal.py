"""The ideal Dirac sampler of the paper's section 4: the true depth at the planned pixels.

The worked example of a sensor (CONTRIBUTING.md): one module, its options class, one registry
line in :mod:`simlunar.sensors`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.registry import Options, option
from simlunar.sensors.base import Acquisition

__all__ = ["IdealOptions", "IdealSampler"]


@dataclass(frozen=True)
class IdealOptions(Options):
    """Options of :class:`IdealSampler`."""

    range_noise_std: float = option(
        0.0,
        doc="standard deviation of additive Gaussian noise on each range sample",
        unit="m",
        ge=0,
    )


class IdealSampler:
    """Reads the true depth at the planned pixels (plus optional Gaussian range noise).

    Parameters
    ----------
    truth : ndarray, shape (rows, cols)
        Ground-truth depth in the guide view (m); finite.
    options : IdealOptions, optional
    """

    name = "ideal"
    needs_plan = True

    def __init__(self, truth: np.ndarray, options: IdealOptions | None = None) -> None:
        truth = np.asarray(truth, dtype=np.float64)
        if truth.ndim != 2:
            raise ValueError(f"truth must have shape (rows, cols), got {truth.shape}")
        if not np.all(np.isfinite(truth)):
            raise ValueError("truth contains NaN or infinite values")
        self.shape = truth.shape
        self.options = options or IdealOptions()
        self._flat = truth.ravel()

    def acquire(self, rc: np.ndarray | None, *, rng=None) -> Acquisition:
        """The truth at ``rc`` ((k, 2) int (row, col)); ``rng`` draws the range noise."""
        if rc is None:
            raise ValueError("the ideal sampler measures planned pixels: rc is required")
        rc = np.asarray(rc)
        values = self._flat[rc[:, 0] * self.shape[1] + rc[:, 1]]
        std = self.options.range_noise_std
        if std > 0:
            values = values + np.random.default_rng(rng).normal(0.0, std, size=len(rc))
        return Acquisition(rc, values, self.shape)
