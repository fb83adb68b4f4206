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
