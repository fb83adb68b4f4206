import matplotlib.pyplot as plt
import numpy as np
import pytest

from simlunar.plotting.headroom import headroom_plot


def _entry(label=""):
    return {
        "label": label,
        "oracle": "oracle_greedy",
        "metric": "mse",
        "strategies": ["wavelet_lloyd", "grid"],
        "captured": {
            "wavelet_lloyd": np.array([0.1, 0.3, np.nan]),  # a seed with no oracle gain: NaN
            "grid": np.array([-0.5, -0.1, -0.3]),
        },
        "seeds": [0, 1, 2],
    }


def test_bars_are_the_means_over_finite_seeds_and_dots_every_seed():
    fig = headroom_plot([_entry()])
    ax = fig.axes[0]
    widths = sorted(round(p.get_width(), 12) for p in ax.patches)
    assert widths == [-0.3, 0.2]  # grid mean -0.3; wavelet_lloyd mean of 0.1, 0.3 (NaN dropped)
    dots = [ln for ln in ax.lines if ln.get_marker() == "o"]
    assert sorted(len(ln.get_xdata()) for ln in dots) == [2, 3]
    # the 0 (uniform layout) and 1 (oracle) references are drawn, and the axis holds both
    refs = {ln.get_xdata()[0] for ln in ax.lines if ln.get_marker() != "o"}
    assert refs == {0.0, 1.0}
    lo, hi = ax.get_xlim()
    assert lo < -0.5 and hi > 1.0
    # top row is the first strategy
    at = dict(zip(ax.get_yticks(), (t.get_text() for t in ax.get_yticklabels())))
    assert at[max(at)] == "Wavelet, Lloyd" and at[min(at)] == "Grid"
    assert "3 terrain seeds" in ax.get_title() and "Oracle greedy" in ax.get_title()
    plt.close(fig)


def test_one_panel_per_point_and_oracle():
    fig = headroom_plot([_entry("terrain: aerial_1"), _entry("terrain: moonyard")])
    assert len(fig.axes) == 2
    assert fig.axes[1].get_title().startswith("terrain: moonyard")
    plt.close(fig)


def test_nothing_to_draw_is_an_error():
    with pytest.raises(ValueError, match="at least one"):
        headroom_plot([])
