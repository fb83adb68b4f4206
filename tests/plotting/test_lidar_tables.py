"""LIDAR study tables: the summary per planner and sample count, and the Markdown / LaTeX
tables (hand-computed means of the rows below)."""

from __future__ import annotations

import numpy as np

from simlunar.plotting.lidar_tables import lidar_summary, lidar_tables


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


def test_lidar_summary_means_times_and_a_band_over_units():
    s = lidar_summary(_rows(), metric="mse")
    g = s["grid"]
    assert list(g["k"]) == [64, 256] and list(g["seconds"]) == [4.0, 12.0]
    # mean over units (1x and 2x) and trials (1.0x and 1.1x)
    assert g["value"][0] == np.mean([1 / 64 * u * t for u in (1, 2) for t in (1.0, 1.1)])
    assert (g["lo"] <= g["value"]).all() and (g["value"] <= g["hi"]).all()
    assert list(g["units"]) == [2, 2]
    one = lidar_summary(_rows(), metric="mse", where={"unit": "0"})["grid"]
    assert list(one["units"]) == [1, 1]


def test_lidar_tables_list_time_and_metrics():
    md, tex = lidar_tables(_rows(), metrics=["mse"], title="t")
    assert "| Planner | k | samples | scan time (s) | MSE |" in md
    assert "| grid | 64 | 64 | 4 |" in md and "| wavelet | 256 | 256 | 24 |" in md
    assert "\\begin{tabular}{lrrrr}" in tex


def test_a_budget_fitted_plan_shows_its_measured_samples_beside_its_nominal_k():
    # a plan fitted to a time or energy budget keeps its nominal k (the curve's point) but
    # measures another count: the table shows both, the mean of the measured one
    rows = [{"unit": str(u), "planner": "wavelet_flash_energy", "k": "1024", "trial": "0",
             "metric": "mse", "value": "0.01", "seconds": "2.0", "samples": str(n)}
            for u, n in ((0, 16379), (1, 16381))]  # fmt: skip
    md, _ = lidar_tables(rows, metrics=["mse"], title="t")
    assert "| wavelet_flash_energy | 1024 | 16380 | 2 | 0.01 |" in md


def test_a_swept_option_makes_separate_points_of_one_curve():
    rows = [
        {"planner": "wavelet", "k": "256", "metric": "mse", "value": str(v), "seconds": str(s),
         "revisits": str(n), "unit": str(u)}
        for u, n, s, v in ((0, 2, 0.4, 2.0), (1, 2, 0.4, 4.0), (2, 4, 0.67, 1.0))
    ]  # fmt: skip
    d = lidar_summary(rows, metric="mse", by="revisits")["wavelet"]
    assert d["seconds"].tolist() == [0.4, 0.67] and d["value"].tolist() == [3.0, 1.0]
    assert d["units"].tolist() == [2, 1]
    assert lidar_summary(rows, metric="mse")["wavelet"]["units"].tolist() == [3]


def test_oracle_rows_are_labelled_bounds():
    oracle = {"unit": "0", "planner": "oracle_greedy", "k": "64", "trial": "0", "metric": "mse",
              "value": "0.001", "seconds": "3.5"}  # fmt: skip
    rows = [*_rows(), oracle]
    md, tex = lidar_tables(rows, metrics=["mse"], title="t")
    assert "| oracle_greedy (a bound) | 64 | 64 | 3.5 | 0.001 |" in md
    assert "bounds, not planners" in md and "oracle\\_greedy (a bound)" in tex
    plain, _ = lidar_tables(_rows(), metrics=["mse"], title="t")
    assert "(a bound)" not in plain and "bounds, not planners" not in plain


def test_a_sweep_of_several_axes_has_a_block_per_point_with_its_seeds_pooled():
    # two sensors x two suns x two terrain seeds: four blocks named by their values (suns by
    # value, 5 before 45), each the mean over its two seeds (hand: (1 + 3) / 2 = 2)
    rows = [
        {"unit": str(u), "study.sensor": sensor, "render.light.elevation_deg": str(sun),
         "terrain_seed": str(seed), "planner": "lloyd", "k": "64", "trial": "0",
         "metric": "mse", "value": str(v + 2 * seed), "seconds": "1"}
        for u, (sensor, sun, seed, v) in enumerate(
            (s, e, t, 1.0 + (s == "flash") * 10 + e)
            for s in ("micromirror_flash", "flash") for e in (45, 5) for t in (0, 1)
        )
    ]  # fmt: skip
    md, _ = lidar_tables(rows, metrics=["mse"], title="t",
                         by=["study.sensor", "render.light.elevation_deg"])  # fmt: skip
    lines = [ln for ln in md.splitlines() if ln.startswith("| sensor=")]
    assert [ln.split(":")[0] for ln in lines] == [
        "| sensor=flash, elevation_deg=5",
        "| sensor=flash, elevation_deg=45",
        "| sensor=micromirror_flash, elevation_deg=5",
        "| sensor=micromirror_flash, elevation_deg=45",
    ]
    # flash under the 5 deg sun: seeds 0 and 1 give 16 and 18, pooled to 17
    assert lines[0].endswith(": lloyd | 64 | 64 | 1 | 17 |")
    assert "unit=" not in md
