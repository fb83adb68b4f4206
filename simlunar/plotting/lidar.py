"""LIDAR figures: a return waveform with its detected returns."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["waveform"]


def waveform(
    range_m: np.ndarray,
    counts: np.ndarray,
    *,
    expected: np.ndarray | None = None,
    returns: dict[str, float] | None = None,
    truth: dict[str, float] | None = None,
    title: str = "",
    ax=None,
):
    """Photon counts of one histogram against range, with the reported returns.

    Parameters
    ----------
    range_m : (bins,) float
        Range of each bin centre (m).
    counts : (bins,) int or float
        Detections per bin.
    expected : (bins,) float or None
        Mean counts per bin (drawn as a line).
    returns : dict name -> range (m) or None
        Reported returns (e.g. ``{"first": 49.0, "last": 50.0}``), drawn as dashed lines.
    truth : dict name -> range (m) or None
        True surface ranges, drawn as dotted lines.
    title : str
    ax : matplotlib Axes or None

    Returns
    -------
    (Figure, Axes)
    """
    if ax is None:
        fig = Figure(figsize=(6.0, 3.2))
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    r = np.asarray(range_m, float)
    ax.step(r, np.asarray(counts, float), where="mid", color="0.3", lw=0.8, label="counts")
    if expected is not None:
        ax.plot(r, expected, color="C0", lw=1.2, label="expected")
    for i, (name, value) in enumerate((returns or {}).items()):
        ax.axvline(value, color=f"C{i + 1}", ls="--", lw=1.0, label=f"{name} return")
    for name, value in (truth or {}).items():
        ax.axvline(value, color="k", ls=":", lw=0.8, label=f"true {name}")
    ax.set_xlabel("range (m)")
    ax.set_ylabel("photon counts per bin")
    if title:
        ax.set_title(title)
    ax.legend(fontsize=7, frameon=False)
    fig.tight_layout()
    return fig, ax
