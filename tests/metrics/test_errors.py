"""Error metrics (simlunar.metrics.errors): hand-computed values, weights, masks, the fast sums."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics import METRICS, metric
from simlunar.metrics._fast import error_sums

TRUTH = np.array([[0.0, 1.0, 2.0], [0.0, 1.0, 4.0]])
RECON = np.array([[1.0, 1.0, 2.0], [0.0, 3.0, 4.0]])  # errors 1, 0, 0 / 0, 2, 0


def test_plain_metrics_hand_computed():
    assert metric("mse", RECON, TRUTH) == pytest.approx(5 / 6)
    assert metric("rmse", RECON, TRUTH) == pytest.approx(np.sqrt(5 / 6))
    assert metric("mae", RECON, TRUTH) == pytest.approx(3 / 6)


def test_grad_weights_from_truth_gradient():
    # numpy.gradient of TRUTH: d/dcol rows [1,1,1] and [1,2,3]; d/drow [0,0,2] twice.
    # |grad| = [[1,1,sqrt5],[1,2,sqrt13]]; weighted errors 1*1 (cell 0,0) + 2*4 (cell 1,1)
    w = np.array([[1, 1, np.sqrt(5)], [1, 2, np.sqrt(13)]])
    expected = (1 * 1 + 2 * 4) / w.sum()
    assert metric("grad", RECON, TRUTH) == pytest.approx(expected)
    assert metric("grad", RECON, TRUTH, weights=np.ones_like(TRUTH)) == pytest.approx(5 / 6)


def test_sal_needs_weights_and_uses_them():
    with pytest.raises(ValueError, match="needs weights="):
        metric("sal", RECON, TRUTH)
    w = np.zeros_like(TRUTH)
    w[1, 1] = 3.0
    assert metric("sal", RECON, TRUTH, weights=w) == pytest.approx(4.0)


def test_mask_and_nan_cells_are_excluded():
    recon = RECON.copy()
    recon[1, 1] = np.nan
    assert metric("mse", recon, TRUTH) == pytest.approx(1 / 5)
    mask = np.ones_like(TRUTH, dtype=bool)
    mask[0, 0] = False
    assert metric("mse", RECON, TRUTH, mask=mask) == pytest.approx(4 / 5)
    with pytest.raises(ValueError, match="no cell"):
        metric("mse", RECON, TRUTH, mask=np.zeros_like(TRUTH, dtype=bool))


def test_fast_sums_match_metric(rng):
    truth = rng.random((20, 30))
    recon = truth + rng.normal(size=truth.shape)
    recon[3, 4] = np.nan
    w = rng.random((2, truth.size))
    count, sse, sae, wse, wsum = error_sums(recon.ravel(), truth.ravel(), w)
    assert count == truth.size - 1
    assert sse / count == pytest.approx(metric("mse", recon, truth), rel=1e-12)
    assert sae / count == pytest.approx(metric("mae", recon, truth), rel=1e-12)
    assert wse[1] / wsum[1] == pytest.approx(
        metric("sal", recon, truth, weights=w[1].reshape(truth.shape)), rel=1e-12
    )


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"name": "psnr"}, "unknown metric 'psnr'; valid: mse, rmse, mae, grad, sal"),
        ({"recon": np.zeros((2, 2))}, "equal 2-D shapes"),
        ({"truth": np.where(TRUTH > 3, np.nan, TRUTH)}, "truth contains NaN"),
        ({"name": "sal", "weights": -np.ones_like(TRUTH)}, "finite and >= 0"),
        ({"name": "sal", "weights": np.ones((3, 3))}, "weights shape"),
        ({"name": "grad", "truth": np.ones_like(TRUTH)}, "sum to zero"),
    ],
)
def test_metric_bad_input(kwargs, match):
    args = {"name": "mse", "recon": RECON, "truth": TRUTH, **kwargs}
    name = args.pop("name")
    with pytest.raises(ValueError, match=match):
        metric(name, **args)


def test_registry():
    # the paper's metrics first, in this order (a metric registered later comes after them)
    assert list(METRICS)[:5] == ["mse", "rmse", "mae", "grad", "sal"]


def test_metrics_take_nested_lists_by_hand():
    """Plain nested lists are arrays too: one cell off by 1 of 4 -> MSE 1/4, RMSE 1/2."""
    from simlunar.metrics import metric

    recon, truth = [[1.0, 2.0], [3.0, 4.0]], [[1.0, 2.0], [3.0, 5.0]]
    assert metric("mse", recon, truth) == pytest.approx(0.25)
    assert metric("rmse", recon, truth) == pytest.approx(0.5)
    assert metric("mae", truth, recon) == pytest.approx(0.25)


@pytest.fixture
def worst_cell():
    """A metric registered for one test: the largest absolute error (m), removed after it."""
    from simlunar.metrics import errors

    errors.register_metric(
        "worst_test", lambda err, w, truth_w: float(np.abs(err).max()), label="WORST", unit="m"
    )
    yield "worst_test"
    for table in (errors.METRICS, errors.METRIC_NAMES, errors.METRIC_UNITS):
        table.pop("worst_test")


def test_a_registered_metric_is_scored_and_named_everywhere(worst_cell):
    from simlunar.metrics import METRIC_NAMES, METRIC_UNITS, METRICS, register_metric
    from simlunar.plotting.style import metric_axis
    from simlunar.study.depth_scores import score_depth
    from simlunar.study.sampling_scores import SamplingEvaluator

    truth = np.arange(12.0).reshape(3, 4)
    recon = truth + np.array([[0, 0, 0, 0], [0, -3, 0, 0], [0, 0, 1, 0]])
    assert metric(worst_cell, recon, truth) == 3.0
    # the scanner's and LIDAR's scores (truth with holes) and the sampling study's
    holed = truth.copy()
    holed[1, 1] = np.nan
    assert score_depth(recon, holed, metrics=[worst_cell]) == {worst_cell: 1.0}
    ev = SamplingEvaluator(truth, np.ones((3, 4)), ["mse", worst_cell], {})
    assert ev(recon, None)[worst_cell] == 3.0
    assert (METRIC_NAMES[worst_cell], METRIC_UNITS[worst_cell]) == ("WORST", "m")
    assert metric_axis(worst_cell) == "WORST error (m)"
    assert list(METRICS)[:5] == ["mse", "rmse", "mae", "grad", "sal"]
    with pytest.raises(ValueError, match="'mse' is registered twice"):
        register_metric("mse", METRICS["mse"], label="MSE", unit="m²")
