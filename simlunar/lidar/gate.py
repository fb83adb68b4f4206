"""The range gate from what an instrument knows: its pose and a reference plane, never the
terrain.

A real receiver opens its time window around where it expects the ground. What it knows is its
own pose (navigation: position and attitude in the world frame) and a reference plane below it:
the map datum (``z = datum_z``; a lander's navigation altitude above the landing site, a rover's
mast height above its wheels' plane) or the plane through an **altimeter reading** along the
boresight (one beam ranged with its window stepped out from the sensor until a return is
found, :func:`simlunar.lidar.scan.altimeter_datum`). The predicted range of a ray is
where it meets that horizontal plane; the window covers it with ``margin_m`` on both sides,
which must cover the terrain's relief about the plane: a return outside its window is lost, as
with a real gate. The cost of a wide margin is time bins (memory and render time) and the
background they integrate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.lidar.waveform import TimeBins
from simlunar.registry import Options, option

__all__ = ["GateOptions", "gate_bins", "plane_ranges"]


@dataclass(frozen=True)
class GateOptions(Options):
    """Where the receiver expects the ground."""

    datum_z_m: float = option(
        0.0,
        doc="height of the reference plane in the world frame, used without an altimeter",
        unit="m",
    )
    altimeter: bool = option(
        False,
        doc="measure the plane first: range the boresight with windows stepped from the sensor "
        "out to max_range_m (a pulse per step) and put the plane through that point",
    )
    max_range_m: float = option(
        2000.0,
        doc="the instrument's largest range: rays that would meet the plane farther (or never) "
        "are gated at it",
        unit="m",
        gt=0,
    )
    min_range_m: float = option(0.1, doc="the instrument's smallest range", unit="m", ge=0)

    def __post_init__(self) -> None:
        super().__post_init__()
        if not np.isfinite(self.datum_z_m):
            raise ValueError(f"datum_z_m must be a finite number, got {self.datum_z_m!r}")
        if not self.min_range_m < self.max_range_m:
            raise ValueError(
                f"min_range_m must be < max_range_m, got {self.min_range_m} >= {self.max_range_m}"
            )


def plane_ranges(origin, directions, *, datum_z: float, options: GateOptions) -> np.ndarray:
    """Predicted range (m) of each ray to the horizontal plane ``z = datum_z``, (n,).

    ``origin`` is (3,) or one per ray (n, 3) (a moving platform). Rays that meet the plane
    beyond ``max_range_m``, behind the sensor or never get ``max_range_m``; nearer than
    ``min_range_m`` get ``min_range_m``.
    """
    d = np.asarray(directions, float).reshape(-1, 3)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    o = np.broadcast_to(np.asarray(origin, float), d.shape)
    height = o[:, 2] - datum_z
    down = -d[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(down > 0, height / down, np.inf)
    r = np.where(r > 0, r, np.inf)
    return np.clip(r, options.min_range_m, options.max_range_m)


def gate_bins(ranges: np.ndarray, *, bin_range_m: float, margin_m: float) -> TimeBins:
    """One window covering predicted ``ranges`` (m) with ``margin_m`` on both sides."""
    r = np.asarray(ranges, float)
    near = max(float(r.min()) - margin_m, 0.0)
    return TimeBins.for_ranges(near, float(r.max()) + margin_m, bin_range_m)
