"""The figures of a scanner result folder, on hand-made rows: pooled means and s.d. by hand,
errors with their ratio to the gray-code scan or against an ablation's swept value, bit error
rates drawn only when some bit was wrong, the sun-to-projector axis when it is proportional."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest

from simlunar.results import scanner_figures as sc
from simlunar.results.captions import Captions


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _row(unit, mode, planner, metric, value, trial=0):
    return {"unit": str(unit), "mode": mode, "planner": planner, "trial": str(trial),
            "metric": metric, "value": str(value)}  # fmt: skip


def test_pooled_mean_sd_and_count_by_hand():
    rows = [_row(0, "gray_code", "", "mse", v, t) for t, v in enumerate((1.0, 2.0, 3.0, "nan"))]
    rows.append(_row(0, "ambiguity_enhancement", "wavelet", "mse", 4.0))
    gray, wave = sc._scanner_pooled(rows, ["mse", "grad"])
    assert (gray["mode"], gray["planner"]) == ("gray_code", "")
    assert gray["mse"] == 2.0 and gray["mse_sd"] == pytest.approx(1.0)  # NaN left out
    assert gray["grad"] is None and gray["grad_sd"] is None
    assert wave["mse"] == 4.0 and wave["mse_sd"] is None  # one value: no s.d.


def _draw(res):
    drawn, captions = [], Captions()
    sc.scanner_figures(res, lambda fig, stem: drawn.append(stem), captions)
    return drawn, captions


def _res(rows, sweep=None, units=None):
    return {"rows": rows, "units": units or [{"index": 0, "sweep": {}}],
            "config": {"study": {"metrics": ["mse"], "trials": 2}, "sweep": sweep or {}}}  # fmt: skip


def test_errors_and_their_ratio_to_gray_code_and_zero_bit_errors_as_a_sentence():
    rows = [
        _row(0, "gray_code", "", "mse", 2.0),
        _row(0, "ambiguity_enhancement", "wavelet", "mse", 1.0),
    ]
    rows += [_row(0, "gray_code", "", f"ber_c{i}", 0.0) for i in range(3)]
    drawn, captions = _draw(_res(rows))
    assert drawn == ["scanner_errors"]
    # not drawn, and why: no bit was wrong (figures/not_drawn.md, the report)
    assert "gray_code_bit_errors" not in captions
    assert captions.not_drawn["gray_code_bit_errors"].startswith("all 3 per-bit gray-code")
    rows += [_row(0, "gray_code", "", "ber_r0", 0.01)]
    drawn, _ = _draw(_res(rows))
    assert drawn == ["scanner_errors", "gray_code_bit_errors"]


def test_an_ablation_draws_errors_against_the_swept_value():
    units = [
        {"index": i, "sweep": {"render.light.irradiance": x}} for i, x in enumerate((1.0, 2.0))
    ]
    rows = []
    for u, x in enumerate((1.0, 2.0)):
        rows += [_row(u, "gray_code", "", "mse", x), _row(u, "gray_code", "", "valid_fraction", 0.9),
                 _row(u, "gray_code", "", "ambient_ratio", 0.3 * x)]  # fmt: skip
    drawn, captions = _draw(_res(rows, {"render.light.irradiance": [1.0, 2.0]}, units))
    assert drawn == ["scanner_vs_irradiance"] and "scanner_vs_irradiance" in captions
    # the sun / projector ratio is 0.3 x the swept irradiance in every unit: a second axis
    factor, label = sc._ambient_axis(rows, units, "render.light.irradiance")
    assert factor == pytest.approx(0.3) and label == "sun / projector white, as the camera sees it"


def test_no_second_axis_unless_proportional():
    units = [{"index": i, "sweep": {"a": x}} for i, x in enumerate((1.0, 2.0))]
    rows = [
        _row(0, "gray_code", "", "ambient_ratio", 0.3),
        _row(1, "gray_code", "", "ambient_ratio", 0.9),
    ]
    assert sc._ambient_axis(rows, units, "a") is None
    assert sc._ambient_axis(rows[:1], units, "a") is None  # a unit without the ratio
    named = [{"index": i, "sweep": {"a": "sun"}} for i in range(2)]
    assert sc._ambient_axis(rows, named, "a") is None  # not a number


def test_every_reconstruction_gets_its_error_figure():
    rows = [
        _row(0, "gray_code", "", "mse", 2.0),
        _row(0, "ambiguity_enhancement", "wavelet", "mse", 1.0),
    ]
    rows = [{**r, "reconstruction": "linear"} for r in rows] + [
        {**r, "reconstruction": "smoothed", "value": str(float(r["value"]) / 2)} for r in rows
    ]
    res = _res(rows)
    res["config"]["study"]["reconstructions"] = ["linear", "smoothed"]
    figs, captions = {}, Captions()
    sc.scanner_figures(res, lambda fig, stem: figs.__setitem__(stem, fig), captions)
    assert list(figs) == ["scanner_errors", "scanner_errors_smoothed"]
    assert figs["scanner_errors_smoothed"]._suptitle.get_text() == "reconstruction: Smoothed"
    assert "Smoothed reconstruction" in captions["scanner_errors_smoothed"]
    # each figure draws its own reconstruction's rows: the bars of smoothed are half linear's
    heights = {
        stem: sorted(p.get_height() for p in fig.axes[0].patches if p.get_height() > 0)
        for stem, fig in figs.items()
    }
    np.testing.assert_allclose(
        heights["scanner_errors_smoothed"], np.asarray(heights["scanner_errors"]) / 2
    )
