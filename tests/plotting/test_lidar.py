"""The waveform figure draws counts, expectation and returns."""

from __future__ import annotations

import numpy as np

from simlunar.plotting.lidar import waveform


def test_waveform_draws_every_element(tmp_path):
    r = np.linspace(45.0, 55.0, 200)
    lam = (
        0.5
        + 20 * np.exp(-0.5 * ((r - 49.0) / 0.1) ** 2)
        + 30 * np.exp(-0.5 * ((r - 50) / 0.1) ** 2)
    )
    counts = np.random.default_rng(0).poisson(lam)
    fig, ax = waveform(
        r,
        counts,
        expected=lam,
        returns={"first": 49.0, "last": 50.0},
        truth={"rock": 49.0},
        title="edge",
    )
    assert len(ax.lines) == 1 + 1 + 2 + 1  # step, expected, two returns, truth
    assert ax.get_title() == "edge"
    fig.savefig(tmp_path / "w.png")
    assert (tmp_path / "w.png").stat().st_size > 1000


def _rows():
    """Two planners, two k, two units (terrain seeds), two trials; CSV-like strings."""
    rows = []
    for unit in (0, 1):
        for planner, scale in (("grid", 1.0), ("wavelet", 2.0)):
            for k, secs in ((64, 4.0), (256, 12.0)):
                for trial in (0, 1):
                    v = scale / k * (1 + unit) * (1 + 0.1 * trial)
                    rows.append({"unit": str(unit), "planner": planner, "k": str(k),
                                 "trial": str(trial), "metric": "mse", "value": str(v),
                                 "seconds": str(secs * scale)})  # fmt: skip
    return rows


def test_error_vs_time_draws_a_curve_per_planner(tmp_path):
    from simlunar.plotting.lidar import error_vs_time

    fig, ax = error_vs_time(_rows(), metric="mse", planners=["wavelet", "grid", "absent"])
    assert [c.get_label() for c in ax.containers] == ["Wavelet", "Grid"]
    assert ax.containers[1].lines[0].get_xdata().tolist() == [4.0, 12.0]
    assert ax.get_xlabel() == "scan time (s)"
    _, ax = error_vs_time(_rows(), metric="mse", x="samples")  # rows without it: k
    assert ax.get_xlabel() == "range samples measured"
    assert ax.containers[0].lines[0].get_xdata().tolist() == [64, 256]
    fig.savefig(tmp_path / "t.png")
