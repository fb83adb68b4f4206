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

**The prior** (opt-in, :func:`prior_ranges`): a navigation datum is a reading, not the truth. With
``datum_sigma_m`` the datum the gate is centred on is ``datum_z_m`` plus an error drawn from the
acquisition's seed (:func:`read_datum`: an altimeter's or the navigation's altitude error, one
draw per acquisition), and the window covers ``prior_sigmas`` of that error either side; with
``max_slope_rad`` the ground may tilt up to that angle about the point where the boresight meets
the datum plane (the altimeter's footprint), and each ray's window covers every plane of that
tilt through it. Neither reads the terrain: a return outside the prior's window is lost, one cut
by its edge is rejected by :attr:`simlunar.lidar.ranging.RangeOptions.edge_sigma`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.lidar.waveform import TimeBins
from simlunar.registry import Options, option

__all__ = ["GateOptions", "gate_bins", "plane_ranges", "prior_ranges", "read_datum"]

#: azimuths of the slope prior's steepest direction sampled (the extreme range over a disk of
#: gradients lies on its rim; 64 samples: within 1 - cos(pi / 64) = 0.12 % of the slope's term)
SLOPE_AZIMUTHS = 64


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
    datum_sigma_m: float = option(
        0.0,
        doc="1-sigma error of the datum as the instrument knows it (an altimeter's or the "
        "navigation's altitude): the gate is centred on datum_z_m plus an error drawn from "
        "the scan's rng (a steered beam without the altimeter) or the render seed (a flash: "
        "one reading for every frame rendered with these options), and its window covers "
        "prior_sigmas of it; 0 = the datum exactly as given",
        unit="m",
        ge=0,
        le=1e3,
    )
    prior_sigmas: float = option(
        3.0, doc="the window covers the datum's error to this many sigmas either side", ge=0, le=10
    )
    max_slope_rad: float = option(
        0.0,
        doc="slope prior: the ground may tilt up to this angle about the point where the "
        "boresight meets the datum plane; each ray's window covers every plane of that tilt "
        "through it (0 = a horizontal plane)",
        unit="rad",
        key_unit="deg",
        ge=0,
        le=1.3,
    )

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


def read_datum(options: GateOptions, rng=None) -> float:
    """The datum the gate is centred on: ``datum_z_m`` plus a draw of ``datum_sigma_m`` (no
    draw, and the datum exactly, when it is 0)."""
    if options.datum_sigma_m == 0:
        return float(options.datum_z_m)
    g = np.random.default_rng(rng)
    return float(options.datum_z_m + options.datum_sigma_m * g.standard_normal())


def prior_ranges(origin, directions, *, datum_z: float, boresight, options: GateOptions):
    """Nearest and farthest range (m) of each ray over the prior's planes: ``(lo, hi)``, (n,).

    The planes pass through ``A``, where the ``boresight`` ray from ``origin`` meets ``z =
    datum_z`` (the altimeter's footprint), shifted by up to ``prior_sigmas x datum_sigma_m`` in
    height and tilted by up to ``max_slope_rad``: ``z = A_z + dz + g . (p_xy - A_xy)`` with
    ``|g| <= tan(max_slope)``. A ray ``o + r d`` meets one at ``r = (A_z + dz - o_z + g . (o_xy
    - A_xy)) / (d_z - g . d_xy)``; for fixed ``g`` it is linear in ``dz`` and, its denominator
    of one sign, its extremes over the disk of ``g`` lie on the rim (sampled at
    :data:`SLOPE_AZIMUTHS` azimuths). A ray that misses one of the planes (behind the sensor,
    or parallel) gets ``max_range_m`` as its far end. Without a prior (both 0) ``lo = hi =``
    :func:`plane_ranges`.
    """
    if options.datum_sigma_m == 0 and options.max_slope_rad == 0:
        r = plane_ranges(origin, directions, datum_z=datum_z, options=options)
        return r, r.copy()
    d = np.asarray(directions, float).reshape(-1, 3)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    o = np.broadcast_to(np.asarray(origin, float), d.shape)
    b = np.asarray(boresight, float).reshape(3)
    o0 = np.asarray(origin, float).reshape(-1, 3)[0]
    if not b[2] < 0:
        raise ValueError("gate: the slope prior needs a boresight that looks down")
    anchor = o0 + (datum_z - o0[2]) / b[2] * b
    phi = np.linspace(0.0, 2 * np.pi, SLOPE_AZIMUTHS, endpoint=False)
    t = np.tan(options.max_slope_rad)
    g = t * np.stack([np.cos(phi), np.sin(phi)], axis=1)  # (m, 2) gradients on the rim
    dz = options.prior_sigmas * options.datum_sigma_m
    lo = np.full(len(d), np.inf)
    hi = np.full(len(d), -np.inf)
    miss = np.zeros(len(d), bool)
    lever = (o[:, :2] - anchor[:2]) @ g.T  # (n, m)
    den = d[:, 2:3] - d[:, :2] @ g.T
    for shift in (-dz, dz):
        num = anchor[2] + shift - o[:, 2:3] + lever
        with np.errstate(divide="ignore", invalid="ignore"):
            r = num / den
        ok = (den < 0) & (r > 0)
        miss |= ~ok.all(axis=1)
        lo = np.minimum(lo, np.where(ok, r, np.inf).min(axis=1))
        hi = np.maximum(hi, np.where(ok, r, -np.inf).max(axis=1))
    hi = np.where(miss, options.max_range_m, hi)
    lo = np.where(np.isfinite(lo), lo, options.max_range_m)
    clip = (options.min_range_m, options.max_range_m)
    return np.clip(lo, *clip), np.clip(hi, *clip)


def gate_bins(ranges: np.ndarray, *, bin_range_m: float, margin_m: float, far=None) -> TimeBins:
    """One window covering predicted ``ranges`` (m) with ``margin_m`` on both sides (``far``:
    the far ends of predicted intervals whose near ends are ``ranges``)."""
    r = np.asarray(ranges, float)
    top = r if far is None else np.asarray(far, float)
    near = max(float(r.min()) - margin_m, 0.0)
    return TimeBins.for_ranges(near, float(top.max()) + margin_m, bin_range_m)
