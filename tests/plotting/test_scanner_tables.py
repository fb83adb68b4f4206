"""Scanner tables: mean error and frames per mode and planner, the ratio to the gray-code scan,
sweep points labelled and pooled, t intervals over units paired with random."""

from __future__ import annotations

import pytest

from simlunar.plotting.scanner_tables import scanner_interval_table, scanner_summary, scanner_tables


def test_scanner_table_means_and_ratio_to_gray_code():
    rows = [
        {
            "unit": "0",
            "mode": "gray_code",
            "planner": "",
            "trial": "0",
            "metric": "mse",
            "value": "4.0",
            "renders": "18",
        },
        {
            "unit": "0",
            "mode": "ambiguity_enhancement",
            "planner": "wavelet",
            "trial": "0",
            "metric": "mse",
            "value": "2.0",
            "renders": "100",
        },
        {
            "unit": "0",
            "mode": "ambiguity_enhancement",
            "planner": "wavelet",
            "trial": "1",
            "metric": "mse",
            "value": "4.0",
            "renders": "120",
        },
    ]
    md, tex = scanner_tables(rows, metrics=["mse"], title="s")
    assert "| Gray code | 4 | – | 18 | 1.000 |" in md
    # mean MSE 3.0 over two trials -> 3/4 of the gray-code MSE; mean frames 110
    assert "| Ambiguity enhancement / Wavelet | 3 | – | 110 | 0.750 |" in md
    assert "Ambiguity enhancement / Wavelet & 3 & -- & 110 & 0.750 \\\\" in tex
    assert "mean of" not in md  # one unit: no pooled rows


def test_scanner_table_labels_sweep_points_and_pools_units():
    def row(unit, seed, mode, planner, value):
        return {
            "unit": unit,
            "seed": seed,
            "mode": mode,
            "planner": planner,
            "trial": "0",
            "metric": "mse",
            "value": value,
            "renders": "10",
        }

    rows = [
        row("0", "5", "gray_code", "", "4.0"),
        row("0", "5", "ambiguity_enhancement", "wavelet", "3.0"),
        row("1", "6", "gray_code", "", "2.0"),
        row("1", "6", "ambiguity_enhancement", "wavelet", "1.0"),
    ]
    md, _ = scanner_tables(rows, metrics=["mse"], title="s")
    assert "| seed=5: Ambiguity enhancement / Wavelet | 3 | – | 10 | 0.750 |" in md
    assert "| seed=6: Ambiguity enhancement / Wavelet | 1 | – | 10 | 0.500 |" in md
    # pooled: mean MSE (3 + 1) / 2 = 2 and mean of the per-unit ratios (0.75 + 0.5) / 2
    assert "| mean of 2 units: Ambiguity enhancement / Wavelet | 2 | – | 10 | 0.625 |" in md
    assert "| mean of 2 units: Gray code | 3 | – | 10 | 1.000 |" in md


def test_scanner_interval_table_pairs_each_unit_with_random():
    def row(unit, mode, planner, trial, value):
        return {"unit": unit, "seed": str(5 + int(unit)), "mode": mode, "planner": planner,
                "trial": trial, "metric": "mse", "value": value, "renders": "10"}  # fmt: skip

    rows = []
    # gray code 10 in every unit; wavelet's trial means 8, 9, 7; random's 9, 9, 8
    for u, (w, r) in enumerate([(("7", "9"), ("9", "9")), (("9", "9"), ("9", "9")),
                                (("7", "7"), ("8", "8"))]):  # fmt: skip
        rows.append(row(str(u), "gray_code", "", "0", "10"))
        for t in range(2):
            rows.append(row(str(u), "ambiguity_enhancement", "wavelet", str(t), w[t]))
            rows.append(row(str(u), "ambiguity_enhancement", "random", str(t), r[t]))
    md, tex = scanner_tables(rows, metrics=["mse"], title="s")
    # MSE / gray code of wavelet: 0.8, 0.9, 0.7 -> mean 0.8, s 0.1, half width 4.302653 x 0.1 / sqrt 3
    h = 4.302653 * 0.1 / 3**0.5
    want = f"0.800 [{0.8 - h:.3f}, {0.8 + h:.3f}]"
    line = next(
        x for x in md.splitlines() if x.startswith("| Ambiguity enhancement / Wavelet | 3 |")
    )
    assert want in line
    # paired with random per unit: 8/9, 9/9, 7/8; below random in 2 of 3 units; random
    # itself: 0.9, 0.9, 0.8 of gray code, mean 0.867
    paired = [8 / 9, 1.0, 7 / 8]
    mean = sum(paired) / 3
    assert f"| {mean:.3f} [" in line.split(want)[1] and line.endswith("| 2 of 3 |")
    assert "| Ambiguity enhancement / Random | 3 | 0.867 [" in md and "1 (reference)" in md
    assert "95 % t interval over units" in md and "MSE / random's, paired" in tex


def test_scanner_interval_table_needs_two_units():
    one = [{"unit": "0", "mode": "ambiguity_enhancement", "planner": "wavelet", "ratio": 0.9,
            "mse": 1.0}]  # fmt: skip
    assert scanner_interval_table(one) == ("", "")


def test_scanner_summary_by_hand():
    rows = [
        {"unit": "0", "mode": "gray_code", "planner": "", "trial": "0", "metric": "mse",
         "value": "4.0", "renders": "18"},
        {"unit": "0", "mode": "ambiguity_enhancement", "planner": "wavelet", "trial": "0",
         "metric": "mse", "value": "1.0", "renders": "30"},
        {"unit": "0", "mode": "ambiguity_enhancement", "planner": "wavelet", "trial": "1",
         "metric": "mse", "value": "2.0", "renders": "50"},
    ]  # fmt: skip
    summary = scanner_summary(rows, metrics=["mse"])
    assert [(s["unit"], s["mode"], s["planner"], s["point"]) for s in summary] == [
        ("0", "gray_code", "", ""),
        ("0", "ambiguity_enhancement", "wavelet", ""),
    ]
    gray, wave = summary
    assert wave["mse"] == pytest.approx(1.5) and wave["renders"] == pytest.approx(40)
    assert gray["mse"] == 4.0 and gray["renders"] == 18
    assert wave["label"] == "Ambiguity enhancement / Wavelet"
    # a sweep value in the rows names the point; a metric not measured is None
    swept = [{**r, "elevation_deg": "30"} for r in rows]
    assert {s["point"] for s in scanner_summary(swept, metrics=["mse", "grad"])} == {
        "elevation_deg=30"
    }
    assert scanner_summary(rows, metrics=["grad"])[0]["grad"] is None
