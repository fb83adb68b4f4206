"""Scanner figures (simlunar.plotting.scanner): error bars, bit-error rates (none said so, small
ones with a unit), each mode/planner pair against the sweep axis."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from simlunar.plotting import scanner


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_scanner_bars_draw_error_bars():
    summary = [
        {"mode": "gray_code", "planner": "", "mse": 2.0, "mse_sd": 0.5, "n": 6},
        {"mode": "ambiguity_enhancement", "planner": "wavelet", "mse": 1.5, "mse_sd": 0.25},
    ]
    _fig, ax = scanner.scanner_bars(summary, metric="mse")
    bars = next(c for c in ax.containers if hasattr(c, "errorbar"))
    assert bars.errorbar is not None
    segs = bars.errorbar.lines[2][0].get_segments()
    np.testing.assert_allclose([s[:, 1] for s in segs], [[1.5, 2.5], [1.25, 1.75]])
    assert ax.get_xticklabels()[0].get_text() == "Gray code\n(n = 6)"
    assert ax.get_ylabel() == "MSE error (m²)"


def test_bit_error_plot_with_no_errors_says_so():
    _fig, ax = scanner.bit_error_rates({"ber_c0": 0.0, "ber_c1": 0.0, "ber_r0": 0.0})
    texts = [t.get_text() for t in ax.texts]
    assert texts == ["no bit errors: all 3 per-bit rates are 0"]
    _fig, ax = scanner.bit_error_rates({"ber_c0": 0.02, "ber_c1": 0.0})
    assert len(ax.texts) == 0 and ax.get_ylim()[0] == 0.0
    assert ax.get_ylabel() == "bit errors per 100 pixels"
    assert list(ax.lines[0].get_ydata()) == pytest.approx([2.0, 0.0])


def test_small_bit_error_rates_get_a_unit_not_an_offset():
    # 1.66e-7 on a fraction axis printed "1e-7" above the axis (the DLP run's figure)
    fig, ax = scanner.bit_error_rates({"ber_c7": 0.0, "ber_c8": 1.66e-7, "ber_r8": 0.0})
    assert ax.get_ylabel() == "bit errors per billion pixels"
    assert max(ax.lines[0].get_ydata()) == pytest.approx(166.0)
    fig.canvas.draw()
    assert ax.yaxis.get_offset_text().get_text() == ""


def _scan_summary(mse_gray, mse_dots, valid):
    return [
        {"mode": "gray_code", "planner": "", "mse": mse_gray, "valid_fraction": valid},
        {"mode": "ambiguity_enhancement", "planner": "wavelet", "mse": mse_dots,
         "mse_sd": mse_dots / 10, "valid_fraction": valid},
    ]  # fmt: skip


def test_scanner_vs_sweep_draws_each_pair_against_the_axis():
    pts = [(0.3, _scan_summary(1e-6, 9e-7, 1.0)), (30, _scan_summary(3e-6, 2e-5, 0.9)),
           (100, _scan_summary(2e-3, 3e-3, 0.01))]  # fmt: skip
    _fig, ax = scanner.scanner_vs_sweep(
        pts, metric="mse", axis_label="sun", secondary=(0.24, "ratio")
    )
    lines = {c.get_label(): c.lines[0] for c in ax.containers}  # errorbar containers
    assert set(lines) == {"Gray code", "Ambiguity enhancement / Wavelet"}
    np.testing.assert_allclose(lines["Gray code"].get_ydata(), [1e-6, 3e-6, 2e-3])
    np.testing.assert_allclose(lines["Gray code"].get_xdata(), [0.3, 30, 100])
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"  # both span > 20x
    (top,) = [c for c in ax.child_axes]
    assert top.get_xlabel() == "ratio"
    _fig, ax = scanner.scanner_vs_sweep(pts, metric="valid_fraction")
    assert ax.get_yscale() == "linear" and ax.get_ylabel() == "valid fraction of guide pixels"
    assert ax.get_ylim() == pytest.approx((-0.02, 1.02))
    # all close to 1: the axis zooms in so 0.994 vs 1.0 is visible
    near = [(x, _scan_summary(1e-6, 1e-6, v)) for x, v in ((1, 1.0), (2, 0.994))]
    _fig, ax = scanner.scanner_vs_sweep(near, metric="valid_fraction")
    lo, hi = ax.get_ylim()
    assert 0.99 < lo < 0.994 and 1.0 < hi < 1.002
    # categories: unconnected markers at 0, 1, 2
    _fig, ax = scanner.scanner_vs_sweep([("a", p[1]) for p in pts], metric="mse")
    (gray,) = [c.lines[0] for c in ax.containers if c.get_label() == "Gray code"]
    assert gray.get_linestyle() == "None" and gray.get_xdata().tolist() == [0, 1, 2]
