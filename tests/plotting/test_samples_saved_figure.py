"""The samples-saved figure: one line per strategy, extrapolated points hollow."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np

from simlunar.plotting import figures as F


def test_samples_saved_plot_lines_and_hollow_extrapolated_points():
    dens = [0.5, 0.25, 0.125]
    factor = {"random": np.ones(3), "grid": np.array([1.5, 2.0, 3.0]), "wavelet": np.ones(3)}
    flag = {"random": np.zeros(3), "grid": np.array([1, 0, 0]), "wavelet": np.zeros(3)}
    fig, ax = F.samples_saved_plot(dens, factor, flag, reference="random", metric="mse")
    lines = [ln for ln in ax.get_lines() if ln.get_label() in ("Grid", "Wavelet", "Random")]
    assert sorted(ln.get_label() for ln in lines) == ["Grid", "Wavelet"]  # not the reference
    grid = next(ln for ln in lines if ln.get_label() == "Grid")
    np.testing.assert_allclose(grid.get_ydata(), [1.5, 2.0, 3.0])
    hollow = [ln for ln in ax.get_lines() if ln.get_markerfacecolor() == "none"]
    assert len(hollow) == 2 and hollow[0].get_xdata().tolist() == [0.5]  # grid's 1/2 only
    assert hollow[1].get_xdata().size == 0  # wavelet: nothing extrapolated
    assert ax.xaxis_inverted() and ax.get_yscale() == "log"
    # the reference and the metric in the title; the y label short (it ran into the suptitle)
    assert "Random" in ax.get_title() and "MSE" in ax.get_title()
    assert ax.get_ylabel() == "samples saved (×)"
    F.close(fig)
