"""A sampling study's result from its labels' steps: each outcome's scores in its (density,
trial) cell, rows reconstruction by reconstruction, eq. 4.3 scores by hand, rounds of the
multi-round labels only, diagnostics and kept grids."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.sensors.base import Acquisition
from simlunar.study.protocol import Outcome
from simlunar.study.sampling import SamplingStudyOptions
from simlunar.study.sampling_result import study_result
from simlunar.study.steps import LabelStep

DENS, KS = [0.5, 0.25], [8, 4]


def _outcome(label, trial, b, mse, *, rounds=1, share=None, grid=None):
    acq = Acquisition(np.empty((0, 2)), np.empty(0), (4, 4))
    scores = {"linear": {"mse": mse}, "shading": {"mse": mse / 2}}
    info = {r: {"guide_frames": (), "exposures": 0} for r in scores}
    if share is not None:
        info["shading"]["shading_share"] = share
    grids = None if grid is None else {"linear": grid}
    return Outcome(label, trial, b, KS[b], acq, scores["linear"], rounds, scores, info, grids)


def _rows(oc):
    return [{"strategy": oc.label, "reconstruction": r, "density": DENS[oc.budget_index],
             "trial": oc.trial, "metric": "mse", "value": s["mse"]}
            for r, s in oc.recon_scores.items()]  # fmt: skip


def _step(label, values, **kw):
    """values[trial][budget] -> the label's step, outcomes in task order."""
    ocs = [
        _outcome(label, t, b, v, **kw) for t, per in enumerate(values) for b, v in enumerate(per)
    ]
    return LabelStep(label, [r for oc in ocs for r in _rows(oc)], ocs)


def test_the_tables_rows_and_scores_of_a_study():
    o = SamplingStudyOptions(strategies=("random", "grid"), densities=DENS, trials=2,
                             metrics=("mse",), reconstructions=("linear", "shading"))  # fmt: skip
    grid = np.ones((4, 4), np.float32)
    random = _step("random", [[4.0, 8.0], [2.0, 6.0]], share=0.5, grid=grid)
    grid_step = _step("grid", [[1.0, 2.0], [1.0, 2.0]], rounds=3)
    res = study_result(o, [random, grid_step], densities=DENS, ks=KS, metrics=["mse"],
                       reconstructions=["linear", "shading"], measuring=["grid"])  # fmt: skip
    np.testing.assert_array_equal(res.errors("mse")["random"], [[4.0, 2.0], [8.0, 6.0]])
    np.testing.assert_array_equal(res.errors("mse", "shading")["grid"], [[0.5, 0.5], [1.0, 1.0]])
    # eq. 4.3 of the first reconstruction: sum_d (1/d) e_random/e_s / sum_d (1/d)
    want = (2 * (3.0 / 1.0) + 4 * (7.0 / 2.0)) / (2 + 4)
    assert res.scores["mse"]["grid"] == pytest.approx(want) and res.scores["mse"]["random"] == 1
    # a strategy's rows reconstruction by reconstruction, each in task order
    assert [(r["reconstruction"], r["trial"], r["density"]) for r in res.rows[:4]] == [
        ("linear", 0, 0.5), ("linear", 0, 0.25), ("linear", 1, 0.5), ("linear", 1, 0.25)
    ]  # fmt: skip
    assert [r["strategy"] for r in res.rows] == ["random"] * 8 + ["grid"] * 8
    # rounds of the multi-round labels only; diagnostics where reported; the kept grids
    assert list(res.rounds) == ["grid"] and (res.rounds["grid"] == 3).all()
    assert list(res.info) == ["shading"] and list(res.info["shading"]["random"]) == [
        "shading_share"
    ]
    assert res.info["shading"]["grid"] == {}
    assert set(res.grids) == {("random", 0, "linear"), ("random", 1, "linear")}
    # without the reference strategy there is no score
    alone = study_result(o, [grid_step], densities=DENS, ks=KS, metrics=["mse"],
                         reconstructions=["linear", "shading"])  # fmt: skip
    assert alone.scores == {} and alone.rounds == {}
