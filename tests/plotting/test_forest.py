"""Forest plot of samples saved vs the uniform layout: the numbers it draws and the figure."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simlunar.plotting.density import NICE_RATIOS
from simlunar.plotting.forest import forest_rows, saved_forest_plot
from simlunar.plotting.style import label

ENTRY = {
    "label": "",
    "metric": "mse",
    "strategies": ["random", "wavelet_lloyd", "grid", "oracle_greedy"],
    "saved": {
        "random": np.array([1.0, 4.0]),
        "wavelet_lloyd": np.array([1.1, 1.2, np.nan]),
        "grid": np.array([np.nan, np.nan]),  # no finite value: left out
        "oracle_greedy": np.array([2.0]),
    },
    "seeds": [0, 1],
}


def test_rows_are_geometric_means_with_t_intervals_in_log_space():
    rows = {r[0]: r for r in forest_rows(ENTRY)}
    assert list(rows) == ["random", "wavelet_lloyd", "oracle_greedy"]
    _, g, lo, hi, v = rows["random"]
    # by hand: logs 0 and ln 4, mean ln 2, s = ln4 / sqrt 2, t(0.975, 1) = 12.7062
    h = 12.706204736 * (math.log(4) / math.sqrt(2)) / math.sqrt(2)
    assert g == pytest.approx(2.0)
    assert (lo, hi) == (
        pytest.approx(math.exp(math.log(2) - h)),
        pytest.approx(math.exp(math.log(2) + h)),
    )
    assert v.tolist() == [1.0, 4.0]
    _, g, lo, hi, v = rows["wavelet_lloyd"]  # the nan seed is left out
    assert g == pytest.approx(math.sqrt(1.1 * 1.2)) and lo < g < hi and v.size == 2
    _, g, lo, hi, _ = rows["oracle_greedy"]  # one seed: no interval
    assert g == lo == hi == 2.0


def test_figure_rows_axis_and_reference_line():
    fig = saved_forest_plot([ENTRY, {**ENTRY, "label": "elevation_deg=30"}])
    axes = fig.axes
    assert len(axes) == 2
    ax = axes[0]
    names = [t.get_text() for t in ax.get_yticklabels()]
    # top to bottom in the tables' row order
    assert names == [label(s) for s in ("random", "wavelet_lloyd", "oracle_greedy")]
    assert list(ax.get_yticks()) == [2, 1, 0]
    lo, hi = ax.get_xlim()
    rows = forest_rows(ENTRY)
    assert lo <= min(r[2] for r in rows) and hi >= max(r[3] for r in rows)
    ticks = list(ax.get_xticks())
    assert ticks and set(ticks) <= set(NICE_RATIOS) and 1 in ticks
    assert ax.get_xscale() == "log"
    assert any(list(line.get_xdata()) == [1.0, 1.0] for line in ax.get_lines())  # the reference
    assert axes[1].get_title().startswith("elevation_deg=30\n")
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_nothing_to_draw_is_an_error():
    with pytest.raises(ValueError, match="at least one entry with a finite value"):
        saved_forest_plot([{**ENTRY, "strategies": ["grid"]}])
    with pytest.raises(ValueError):
        saved_forest_plot([])
