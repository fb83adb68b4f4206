"""Flat LIDAR scans joined one after the other (the frames of a flash, the rounds of a
multi-round plan): each one's times start where the previous ended."""

from __future__ import annotations

import dataclasses

import numpy as np

from simlunar.lidar.returns import LidarScan

__all__ = ["concat_scans", "flat_scan", "join_scans", "subset_scan"]


def _or(a, n, fill=0):
    return np.full(n, fill) if a is None else np.asarray(a).ravel()


def flat_scan(s: LidarScan) -> LidarScan:
    """The scan as flat (n,) arrays in its own order (``order`` 0..n-1), times and return
    counts filled (0) where it has none."""
    n = s.ranges.size
    return LidarScan(
        s.ranges.ravel(),
        s.valid.ravel(),
        s.points.reshape(-1, 3),
        s.photons.ravel(),
        np.arange(n),
        s.seconds,
        s.frames,
        times=_or(s.times, n, 0.0).astype(float),
        returns=_or(s.returns, n).astype(np.int64),
        energy_j=s.energy_j,
    )


def subset_scan(s: LidarScan, keep: np.ndarray) -> LidarScan:
    """The points of a flat scan where ``keep`` (bool, (n,)) holds; time, frames and energy
    kept."""
    return LidarScan(
        s.ranges[keep],
        s.valid[keep],
        s.points[keep],
        s.photons[keep],
        np.arange(int(keep.sum())),
        s.seconds,
        s.frames,
        times=s.times[keep],
        returns=s.returns[keep],
        energy_j=s.energy_j,
    )


def join_scans(scans, gaps_s=None) -> LidarScan:
    """Scans one after the other as one flat scan: each one's times start where the previous
    ended, plus ``gaps_s[i]`` (s, e.g. re-pointing) before scan ``i + 1``.

    Parameters
    ----------
    scans : sequence of LidarScan
    gaps_s : sequence of float, length ``len(scans) - 1``, optional (default zeros)

    Returns
    -------
    LidarScan
        Flat (n,) arrays in scan order, ``order`` 0..n-1, ``seconds`` the sum of the scans'
        and the gaps, ``frames`` and ``energy_j`` their sums.
    """
    gaps = np.zeros(max(len(scans) - 1, 0)) if gaps_s is None else np.asarray(gaps_s, float)
    if len(gaps) != max(len(scans) - 1, 0) or (gaps < 0).any():
        raise ValueError(f"need {len(scans) - 1} gaps >= 0 s between {len(scans)} scans")
    merged = concat_scans([flat_scan(s) for s in scans], gaps)
    return dataclasses.replace(merged, seconds=merged.seconds + float(gaps.sum()))


def concat_scans(scans: list[LidarScan], gaps=None) -> LidarScan:
    """The frames one after the other: each one's times start where the previous ended."""
    cat = np.concatenate
    n = sum(s.ranges.size for s in scans)
    start = np.cumsum([0.0] + [s.seconds for s in scans[:-1]])
    if gaps is not None:
        start = start + np.cumsum([0.0, *gaps])
    return LidarScan(
        cat([s.ranges for s in scans]),
        cat([s.valid for s in scans]),
        cat([s.points for s in scans]),
        cat([s.photons for s in scans]),
        np.arange(n),
        float(sum(s.seconds for s in scans)),
        int(sum(s.frames for s in scans)),
        times=cat([t0 + s.times for t0, s in zip(start, scans)]),
        returns=cat([s.returns for s in scans]),
        energy_j=float(sum(s.energy_j for s in scans)),
    )
