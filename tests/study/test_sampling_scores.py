"""The sampling study's one-pass scores: the library's metric definitions, interior scores on the
interior cells only, score names per region, and errors for weights that vanish."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics import depth_gradient_weights, metric
from simlunar.study.sampling_scores import INTERIOR_SUFFIX, SamplingEvaluator, scored_metrics


def _case(rows=12, cols=15, seed=3):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:rows, 0:cols] / 4.0
    depth = np.sin(x) * np.cos(y) + 0.1 * x
    recon = depth + rng.normal(0.0, 0.05, depth.shape)
    image = (0.5 + 0.3 * np.cos(2 * x + y)).astype(np.float32)
    return depth, recon, image


def test_scored_metric_names_per_region():
    assert scored_metrics(["mse", "grad"], "full") == ["mse", "grad"]
    assert scored_metrics(["mse"], "interior") == ["mse" + INTERIOR_SUFFIX] == ["mse_interior"]
    assert scored_metrics(["mse", "mae"], "both") == ["mse", "mae", "mse_interior", "mae_interior"]


def test_one_pass_scores_equal_the_library_metrics():
    depth, recon, image = _case()
    ev = SamplingEvaluator(depth, image, ["mse", "rmse", "mae", "grad"], {})
    got = ev(recon, None)
    err = recon - depth
    assert got["mse"] == pytest.approx(np.mean(err**2), rel=1e-12)
    assert got["rmse"] == pytest.approx(np.sqrt(np.mean(err**2)), rel=1e-12)
    assert got["mae"] == pytest.approx(np.mean(np.abs(err)), rel=1e-12)
    want = metric("grad", recon, depth, weights=depth_gradient_weights(depth))
    assert got["grad"] == pytest.approx(want, rel=1e-10)


def test_interior_scores_use_the_interior_cells_only():
    depth, recon, image = _case()
    inner = np.zeros(depth.shape, bool)
    inner[3:-3, 4:-4] = True
    recon = recon.copy()
    recon[0, 0] += 100.0  # a border error the interior must not see
    got = SamplingEvaluator(depth, image, ["mse", "mae"], {}, inner, "both")(recon, None)
    assert set(got) == {"mse", "mae", "mse_interior", "mae_interior"}
    assert got["mse_interior"] == pytest.approx(np.mean((recon - depth)[inner] ** 2), rel=1e-12)
    assert got["mse"] > 100.0**2 / depth.size > got["mse_interior"]
    only = SamplingEvaluator(depth, image, ["mse"], {}, inner, "interior")(recon, None)
    assert only == {"mse_interior": got["mse_interior"]}


def test_weights_that_vanish_are_errors():
    depth, _, image = _case()
    with pytest.raises(ValueError, match="'grad' weights are zero everywhere"):
        SamplingEvaluator(np.ones_like(depth), image, ["grad"], {})
    with pytest.raises(ValueError, match="no finite cell"):
        SamplingEvaluator(depth, image, ["mse"], {})(np.full(depth.shape, np.nan), None)


def test_a_metric_beyond_the_one_pass_sums_is_scored_by_its_own_definition(monkeypatch):
    # a metric registered in METRICS that the one-pass kernel does not know (here the
    # largest absolute error) is scored by metrics.metric on the same cells: a new metric is
    # its METRICS entry, with no branch in the study
    from simlunar.metrics import errors

    monkeypatch.setitem(errors.METRICS, "maxabs", lambda err, w, truth_w: float(np.abs(err).max()))
    depth, recon, image = _case()
    inner = np.zeros(depth.shape, bool)
    inner[3:-3, 4:-4] = True
    recon = recon.copy()
    recon[0, 0] += 7.0  # the border's error, out of the interior
    recon[5, 6] = np.nan  # not evaluated (outside the hull with outside="nan")
    got = SamplingEvaluator(depth, image, ["mse", "maxabs"], {}, inner, "both")(recon, None)
    err = np.abs(recon - depth)
    assert got["maxabs"] == pytest.approx(7.0, abs=0.3) == np.nanmax(err)
    assert got["maxabs_interior"] == np.nanmax(err[inner]) < 1.0
    assert got["mse"] == pytest.approx(np.nanmean(err**2), rel=1e-12)
