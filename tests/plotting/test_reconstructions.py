"""The samples-saved-vs-linear figure against a sweep axis (one panel per strategy)."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

from simlunar.plotting.reconstructions import MAX_PANELS, reconstruction_saved_vs_sweep


def _points():
    nan = math.nan
    return [
        (15, {"shading": {"grid": (1.8, 1.5, 2.2), "random": (1.6, nan, nan)},
              "smoothed": {"grid": 1.1, "random": 1.05}}),
        (60, {"shading": {"grid": (1.1, 1.0, 1.2), "random": (1.0, nan, nan)},
              "smoothed": {"grid": 1.1, "random": 1.0}}),
    ]  # fmt: skip


def test_one_panel_per_strategy_one_series_per_reconstruction():
    fig, axes = reconstruction_saved_vs_sweep(
        _points(), strategies=["grid", "random"], reconstructions=["shading", "smoothed"],
        axis_label="sun elevation (deg)",
    )  # fmt: skip
    try:
        assert [ax.get_title() for ax in axes] == ["Grid", "Random"]
        lines = [ln for ln in axes[0].get_lines() if ln.get_label() in ("Shading", "Smoothed")]
        ys = {ln.get_label(): list(ln.get_ydata()) for ln in lines}
        assert ys == {"Shading": [1.8, 1.1], "Smoothed": [1.1, 1.1]}
        assert axes[0].get_yscale() == "log"
        lo, hi = axes[0].get_ylim()
        assert lo < 1.0 < 2.2 < hi  # 1 (linear) and the interval's top in view
        # the interval of shading on grid is drawn; random has none
        assert len(axes[0].collections) >= 1
        legend = fig.legends[0]
        assert [t.get_text() for t in legend.get_texts()] == ["Shading", "Smoothed"]
    finally:
        plt.close(fig)


def test_categorical_axis_and_panel_cap():
    pts = [("sun", _points()[0][1]), ("camera", _points()[1][1])]
    strategies = ["grid", "random", "a", "b", "c", "d"]
    fig, axes = reconstruction_saved_vs_sweep(
        pts, strategies=strategies, reconstructions=["shading"], axis_label="light"
    )
    try:
        # every planner of the study gets its panel (a cap of 4 dropped the fifth, wavelet)
        assert [ax.get_title() for ax in axes] == ["Grid", "Random", "A", "B", "C", "D"]
        assert [t.get_text() for t in axes[0].get_xticklabels()] == ["Sun", "Camera-centred light"]
        missing = next(ln for ln in axes[2].get_lines() if ln.get_label() == "Shading")
        assert np.isnan(missing.get_ydata()).all()  # no value for that strategy: nothing drawn
    finally:
        plt.close(fig)
    many = [f"s{i}" for i in range(MAX_PANELS + 3)]
    fig, axes = reconstruction_saved_vs_sweep(pts, strategies=many, reconstructions=["shading"])
    try:
        assert len(axes) == MAX_PANELS
    finally:
        plt.close(fig)
    with pytest.raises(ValueError, match="needs points"):
        reconstruction_saved_vs_sweep([], strategies=["grid"], reconstructions=["shading"])


def test_category_labels_name_only_what_differs():
    from simlunar.plotting.reconstructions import category_labels

    lights = [{"kind": "sun", "elevation_deg": 30.0, "azimuth_deg": 135.0},
              {"kind": "sun", "elevation_deg": 60.0, "azimuth_deg": 135.0}, {"kind": "camera"}]  # fmt: skip
    assert category_labels(lights) == ["Sun 30°", "Sun 60°", "Camera-centred light"]
    assert category_labels([5, 30]) == [5, 30]


def test_reconstruction_panels_titles_do_not_overlap_with_many_reconstructions():
    """Four reconstructions and a long planner name (five narrow columns): no two titles
    share a pixel (the samples panel's one-line title ran into the error panel beside it)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from simlunar.plotting.reconstructions import reconstruction_panels

    rng = np.random.default_rng(0)
    truth = 50.0 + rng.random((50, 80))
    recons = {n: truth + 0.01 * rng.random((50, 80))
              for n in ("linear", "smoothed", "shading_sun", "shading")}  # fmt: skip
    rows, cols = rng.integers(0, 50, 60), rng.integers(0, 80, 60)
    fig, axes = reconstruction_panels(rng.random((50, 80)), truth, recons, (rows, cols),
                                      planner="lloyd_uniform", density_label="k/N = 1/64",
                                      spacing_m=1.0)  # fmt: skip
    assert axes.shape == (2, 5)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    boxes = [ax.title.get_window_extent(canvas.get_renderer()) for ax in axes.ravel()]
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :])
