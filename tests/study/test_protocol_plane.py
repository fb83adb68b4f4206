"""The study protocol on a plane (where Delaunay-linear reconstruction is exact): task order,
one seed pair per (label, trial, budget), planners with and without a plan, multi-round
planners, forked workers that give the same scores, and the input checks."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.sensors.base import Acquisition
from simlunar.sensors.ideal import IdealSampler
from simlunar.study.protocol import Outcome, Trials, run_protocol

ROWS, COLS = 6, 8
R, C = np.mgrid[0:ROWS, 0:COLS]
PLANE = 0.5 * R - 0.25 * C + 3.0
CORNERS = np.array([[0, 0], [0, COLS - 1], [ROWS - 1, 0], [ROWS - 1, COLS - 1]])


def corners_plus(k, rng):
    """The four corners (so every cell is inside the hull) and k - 4 random other pixels."""
    others = np.random.default_rng(rng).choice(ROWS * COLS, size=k + 4, replace=False)
    rc = [tuple(x) for x in CORNERS]
    for f in others:
        p = (int(f // COLS), int(f % COLS))
        if p not in rc and len(rc) < k:
            rc.append(p)
    return np.array(rc[:k])


def max_error(recon, acq):
    return {"max_abs": float(np.abs(recon - PLANE).max()), "k": len(acq.values)}


def _trials(**kw):
    seen = []

    def seeds(label, trial, bi):
        seen.append((label, trial, bi))
        return 100 * trial + bi, None

    args = {"planners": {"a": corners_plus, "b": corners_plus}, "ks": [4, 10], "trials": 2,
            "seeds": seeds}  # fmt: skip
    return Trials(**{**args, **kw}), seen


def test_every_label_trial_and_budget_in_order_exact_on_a_plane():
    trials, seen = _trials()
    out = list(run_protocol(IdealSampler(PLANE), trials, max_error))
    assert [(o.label, o.trial) for task in out for o in task[:1]] == [
        ("a", 0),
        ("a", 1),
        ("b", 0),
        ("b", 1),
    ]
    assert seen == [(lab, t, bi) for lab in "ab" for t in range(2) for bi in range(2)]
    for task in out:
        assert [(o.budget_index, o.k) for o in task] == [(0, 4), (1, 10)]
        for o in task:
            assert isinstance(o, Outcome) and o.rounds == 1
            assert o.scores == {"max_abs": pytest.approx(0.0, abs=1e-12), "k": o.k}
            assert len(o.acquisition.values) == o.k


class FullScan:
    """A sensor that needs no plan: it measures every pixel but the first column."""

    name, needs_plan = "full", False

    def acquire(self, rc, *, rng=None):
        assert rc is None
        m = PLANE.copy()
        m[:, 0] = np.nan
        return Acquisition.from_map(m, frames=7)


def test_a_sensor_without_a_plan_and_the_outside_policy():
    trials, _ = _trials(planners={"scan": None}, ks=[0], trials=1)
    (task,) = run_protocol(
        FullScan(), trials, lambda recon, acq: {"nan": int(np.isnan(recon).sum())}
    )
    assert task[0].acquisition.frames == 7 and task[0].scores == {"nan": 0}  # nearest fill
    (task,) = run_protocol(FullScan(), trials, lambda recon, acq: {"nan": int(np.isnan(recon).sum())},
                           outside="nan")  # fmt: skip
    assert task[0].scores == {"nan": ROWS}  # the first column is outside the hull


class TwoRounds:
    """A planner that measures while it plans (asks the sensor back)."""

    measures = True

    def acquire(self, k, sensor, plan_rng, sensor_rng):
        first = sensor.acquire(CORNERS, rng=sensor_rng)
        more = sensor.acquire(corners_plus(k, plan_rng)[4:], rng=sensor_rng)
        rc = np.concatenate([first.rc, more.rc])
        return Acquisition(rc, np.concatenate([first.values, more.values]), first.shape), 2


def test_a_multi_round_planner_reports_its_rounds():
    trials, _ = _trials(planners={"seq": TwoRounds()}, trials=1)
    (task,) = run_protocol(IdealSampler(PLANE), trials, max_error)
    assert [o.rounds for o in task] == [2, 2]
    assert [o.scores["k"] for o in task] == [4, 10]


def test_forked_workers_give_the_same_scores_without_the_arrays():
    one = list(run_protocol(IdealSampler(PLANE), _trials()[0], max_error))
    two = list(run_protocol(IdealSampler(PLANE), _trials()[0], max_error, workers=2))
    assert [[o.scores for o in t] for t in one] == [[o.scores for o in t] for t in two]
    assert all(o.acquisition.rc.shape == (0, 2) for t in two for o in t)
    assert all(o.acquisition.shape == (ROWS, COLS) for t in two for o in t)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Trials({"a": None}, [1], 0, lambda *a: (0, 0)),
         "^trials must be an integer >= 1, got 0$"),
        (lambda: Trials({"a": None}, [1], True, lambda *a: (0, 0)),
         "^trials must be an integer >= 1, got True$"),
        (lambda: Trials({}, [1], 1, lambda *a: (0, 0)),
         "^the protocol needs at least one planner label$"),
        (lambda: run_protocol(None, _trials()[0], max_error, outside="zero"),
         "^unknown outside policy 'zero'; valid: nearest, nan$"),
        (lambda: run_protocol(None, _trials()[0], max_error, workers=0),
         "^workers must be an integer >= 1, got 0$"),
        (lambda: run_protocol(None, _trials()[0], max_error, workers=2.0),
         r"^workers must be an integer >= 1, got 2\.0$"),
    ],
)  # fmt: skip
def test_refusals(make, message):
    with pytest.raises(ValueError, match=message):
        make()
