"""Error and score curves (simlunar.plotting.density): trial means reach the axes, log axes,
categories unconnected, units and the band explained, ax= composes, deterministic saves."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from simlunar.plotting import density
from simlunar.plotting.layout import save


def rows():
    out = []
    for s, scale in (("random", 2.0), ("wavelet", 1.0)):
        for d in (0.5, 0.25, 0.125):
            for t, noise in enumerate((0.9, 1.1)):
                out.append(
                    {
                        "strategy": s,
                        "density": str(d),
                        "trial": str(t),
                        "metric": "mse",
                        "value": str(scale / d * noise),
                        "unit": "0",
                    }
                )
    return out


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_mean_error_by_density_is_the_trial_mean():
    d, m, sd = density.mean_error_by_density(rows(), metric="mse", strategy="wavelet")
    assert d.tolist() == [0.5, 0.25, 0.125]
    np.testing.assert_allclose(m, [2.0, 4.0, 8.0])  # mean of 0.9x and 1.1x
    np.testing.assert_allclose(sd, np.array([2.0, 4.0, 8.0]) * np.std([0.9, 1.1], ddof=1))
    d, m, _ = density.mean_error_by_density(
        rows(), metric="mse", strategy="wavelet", where={"unit": 1}
    )
    assert d.size == 0


def test_error_vs_density_plots_each_strategy_on_log_axes():
    _fig, ax = density.error_vs_density(rows(), metric="mse")
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    assert set(lines) == {"Random", "Wavelet"}
    np.testing.assert_allclose(lines["Random"].get_ydata(), [4.0, 8.0, 16.0])
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    assert ax.xaxis_inverted()


def test_ax_argument_draws_into_the_given_axes():
    fig, axes = plt.subplots(1, 2)
    f2, a2 = density.error_vs_density(rows(), metric="mse", ax=axes[1])
    assert f2 is fig and a2 is axes[1]
    _f3, a3 = density.score_vs_sweep(
        [(5, {"mse": {"wavelet": 1.2}}), (30, {"mse": {"wavelet": 1.4}})],
        ax=axes[0],
        axis_label="elevation",
    )
    assert a3 is axes[0]
    (line,) = [ln for ln in a3.get_lines() if ln.get_label() == "Wavelet"]
    assert line.get_xdata().tolist() == [5.0, 30.0]
    assert line.get_ydata().tolist() == [1.2, 1.4]


def test_score_vs_sweep_with_labels_draws_categories_unconnected():
    _fig, ax = density.score_vs_sweep(
        [
            ("lambert", {"mse": {"grid": 0.9, "wavelet": 1.0}}),
            ("oren_nayar", {"mse": {"grid": 1.1}}),
        ]
    )
    assert [t.get_text() for t in ax.get_xticklabels()] == ["Lambert", "Oren-Nayar"]
    grid = next(ln for ln in ax.get_lines() if ln.get_label() == "Grid")
    assert grid.get_linestyle() == "None"  # no line between two categories
    assert grid.get_ydata().tolist() == [0.9, 1.1]
    # side by side: each strategy's markers sit off the category centre, in opposite ways
    wav = next(ln for ln in ax.get_lines() if ln.get_label() == "Wavelet")
    assert grid.get_xdata()[0] < 0 < wav.get_xdata()[0]
    assert ax.get_ylabel() == "MSE score (random = 1)"


def test_numeric_sweep_draws_lines():
    _fig, ax = density.score_vs_sweep([(5, {"mse": {"grid": 1}}), (30, {"mse": {"grid": 2}})])
    (line,) = [ln for ln in ax.get_lines() if ln.get_label() == "Grid"]
    assert line.get_linestyle() == "-"


def test_error_axes_have_units_and_the_band_is_explained():
    _fig, ax = density.error_vs_density(rows(), metric="mse")
    assert ax.get_ylabel() == "MSE error (m²)"
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["Random", "Wavelet", density.BAND_LABEL]
    # no spread (one trial): no band, so no band entry
    one = [r for r in rows() if r["trial"] == "0"]
    _fig, ax = density.error_vs_density(one, metric="mse")
    assert density.BAND_LABEL not in [t.get_text() for t in ax.get_legend().get_texts()]


def test_save_is_deterministic():
    a = dict(save(density.error_vs_density(rows(), metric="mse")[0], "x", ("png", "pdf")))
    b = dict(save(density.error_vs_density(rows(), metric="mse")[0], "x", ("png", "pdf")))
    assert a["png"][:8] == b"\x89PNG\r\n\x1a\n" and a["pdf"][:5] == b"%PDF-"
    assert a == b


def test_where_with_a_list_pools_units():
    # unit 1: the same design at 3x the error; pooling both units averages four values
    both = rows() + [dict(r, unit="1", value=str(3 * float(r["value"]))) for r in rows()]
    d, m, sd = density.mean_error_by_density(
        both, metric="mse", strategy="wavelet", where={"unit": [0, 1]}
    )
    assert d.tolist() == [0.5, 0.25, 0.125]
    vals = np.array([0.9, 1.1, 2.7, 3.3])  # x (1/d) for trials 0, 1 of units 0 and 1
    np.testing.assert_allclose(m, np.array([2.0, 4.0, 8.0]) * vals.mean())
    np.testing.assert_allclose(sd, np.array([2.0, 4.0, 8.0]) * vals.std(ddof=1))
    _d, m1, _ = density.mean_error_by_density(
        both, metric="mse", strategy="wavelet", where={"unit": (1,)}
    )
    np.testing.assert_allclose(m1, [6.0, 12.0, 24.0])


def test_ratio_ticks_thin_to_every_other_keeping_one():
    fig, ax = plt.subplots()
    ax.set_xscale("log", base=2)
    # 0.5 .. 2: 0.5, 0.67, 0.8, 1, 1.25, 1.5, 2 -> 7 ticks, all kept
    assert density.ratio_ticks(ax.xaxis, 0.5, 2.0) == [0.5, 0.67, 0.8, 1, 1.25, 1.5, 2]
    # 0.25 .. 4: 11 nice ratios -> every other one counted from 1
    ticks = density.ratio_ticks(ax.yaxis, 0.25, 4.0)
    assert ticks == [0.25, 0.4, 0.67, 1, 1.5, 3]
    assert ax.yaxis.get_major_formatter()(0.67, 0) == "0.67"  # plain numbers, not 2^x
    assert list(ax.yaxis.get_majorticklocs()) == ticks
    assert ax.yaxis.get_minor_locator().tick_values(0.25, 4.0) == []
    plt.close(fig)
