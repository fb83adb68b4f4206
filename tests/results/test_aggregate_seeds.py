"""Pooling a sampling experiment over terrain seeds, on hand-made results: units grouped into
points, error arrays in results order, scores and samples saved of a strategy with half the
error of random on a 1/k error curve (score 2, the reference needing twice the samples)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.results.aggregate import (
    SCORES_CSV_COLUMNS,
    SEED_AXIS,
    density_panels,
    error_arrays,
    group_points,
    paired_saved_entries,
    scores_csv_rows,
    summarise,
    sweep_value,
)

DENSITIES = [0.5, 0.25, 0.125]
SHAPE = (16, 16)  # 256 pixels: k = 128, 64, 32


def _record(elev, seed, strategies=("random", "half")):
    return {
        "sweep": {"render.light.elevation_deg": elev, SEED_AXIS: seed},
        "config": {"name": "t", "terrain": {"seed_index": seed},
                   "study": {"strategies": list(strategies), "metrics": ["mse"]}},
        "meta": {"shape": list(SHAPE)},
        "scores": {"mse": {"random": 1.0, "half": 2.0}},
    }  # fmt: skip


def _rows(unit, strategies=("random", "half"), trials=2):
    rows = []
    for s in strategies:
        for d in DENSITIES:
            k = int(d * 256)
            for t in range(trials):
                e = (1.0 if s == "random" else 0.5) * 100.0 / k  # error ~ 1 / k
                rows.append({"unit": str(unit), "strategy": s, "density": str(d), "k": str(k),
                             "trial": str(t), "metric": "mse", "value": repr(e)})  # fmt: skip
    return rows


RECORDS = [_record(30, 0), _record(30, 1), _record(60, 0), _record(60, 1)]
ROWS = [r for i in range(4) for r in _rows(i)]


def test_units_differing_only_by_terrain_seed_form_one_point():
    points = group_points(RECORDS)
    assert [p.unit_indices for p in points] == [[0, 1], [2, 3]]
    assert [p.seeds for p in points] == [[0, 1], [0, 1]]
    assert points[0].sweep == {"render.light.elevation_deg": 30}
    assert points[0].label == "elevation_deg=30" and points[0].n_pixels == 256
    assert points[0].metrics == ["mse"] and points[0].strategies == ["random", "half"]


def test_error_arrays_in_results_order():
    p = group_points(RECORDS)[1]
    dens, ks, errs = error_arrays(ROWS, p, "mse")
    assert dens == DENSITIES and ks == [128, 64, 32]
    assert errs["half"].shape == (2, 3, 2)  # seeds, densities, trials
    np.testing.assert_allclose(errs["random"][1, :, 0], [100 / 128, 100 / 64, 100 / 32])
    missing = [r for r in ROWS if (r["unit"], r["strategy"], r["trial"]) != ("3", "half", "1")]
    with pytest.raises(
        ValueError, match=r"^results of 'elevation_deg=60': missing errors of 'half' \(mse\)$"
    ):
        error_arrays(missing, p, "mse")


def test_half_the_error_scores_two_and_saves_half_the_samples():
    points = summarise(RECORDS, ROWS, seed=1, n_boot=200)
    p = points[0]
    assert p.densities == DENSITIES and p.ks == [128, 64, 32]
    score, lo, hi = p.intervals["mse"].interval("half")
    # eq. 4.3: the density-weighted mean of e_random / e_s = 2 at every density; no spread
    assert (score, lo, hi) == pytest.approx((2.0, 2.0, 2.0))
    assert p.intervals["mse"].interval("random") == pytest.approx((1.0, 1.0, 1.0))
    # e = 100 / k: random reaches half's error 50 / k with 2 k samples (interpolated at the
    # two denser budgets; at k = 128 it would need 256, past random's own densest budget)
    saved = p.saved["random"]
    np.testing.assert_allclose(saved.factor["half"][1:], 2.0)
    assert saved.summary["half"] == pytest.approx(2.0)
    np.testing.assert_allclose(p.mean_errors["mse"]["half"], [50 / 128, 50 / 64, 50 / 32])


def test_scores_csv_rows_per_seed_then_pooled():
    points = summarise(RECORDS[:2], ROWS[: len(ROWS) // 2], seed=1, n_boot=50)
    rows = scores_csv_rows(points, RECORDS[:2])
    assert all(list(r) == SCORES_CSV_COLUMNS for r in rows)
    per_seed = [r for r in rows if r["terrain_seed"] != "all"]
    assert [(r["terrain_seed"], r["strategy"], r["score"]) for r in per_seed] == [
        (0, "random", 1.0),
        (0, "half", 2.0),
        (1, "random", 1.0),
        (1, "half", 2.0),
    ]
    pooled = [r for r in rows if r["terrain_seed"] == "all"]
    assert [r["strategy"] for r in pooled] == ["random", "half"]
    assert pooled[1]["score"] == pytest.approx(2.0) and pooled[1]["ci_low"] == pytest.approx(2.0)
    assert paired_saved_entries(points) == []  # no lloyd_uniform: nothing paired


def test_sweep_values_and_density_panels():
    assert sweep_value({"sweep": {"a": 5}}, "a") == 5
    assert sweep_value({"sweep": {"a": None}}, "a") == "preset default"
    assert sweep_value({"sweep": {"a": {"kind": "sun", "e": 1}}}, "a") == "sun"
    assert sweep_value({"sweep": {"a": {"x": 1}}}, "a") == '{"x": 1}'
    panels = density_panels(RECORDS)
    assert [len(units) for _, units in panels] == [2, 2]
    assert panels[0][1][1] is RECORDS[1]
