"""Reconstruction error metrics of the sampling study (paper section 4.1).

``metric(name, recon, truth, *, weights=None, mask=None)`` with names in ``METRICS``:

- ``mse``, ``rmse``, ``mae``: plain mean squared / root mean squared / mean absolute error.
- ``grad``: gradient-weighted MSE, sum w e^2 / sum w with w = |grad truth| (``numpy.gradient``
  of the ground-truth depth), so errors at depth discontinuities count most.
- ``sal``: saliency-weighted MSE with w = the Itti-Koch saliency map. The map is not computed
  here: pass ``weights=feature_map("saliency", guide_image)``. The study computes it on the guide
  image (the intensity image the planners see), as the paper's Saliency Toolbox map.

Cells where ``recon`` is NaN (outside the hull with ``outside="nan"``) or ``mask`` is False are
excluded.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = [
    "METRICS",
    "METRIC_NAMES",
    "METRIC_UNITS",
    "depth_gradient_weights",
    "metric",
    "register_metric",
]


def _weighted_mse(err, w):
    total = float(w.sum())
    if total <= 0:
        raise ValueError("metric weights sum to zero over the evaluated cells")
    # np.sum (pairwise) rather than np.dot: BLAS splits a dot product over its threads, so
    # the last bits would depend on the thread count (a run with --workers 2 would differ)
    return float(np.sum(w * (err * err)) / total)


def _mse(err, w, truth_w):
    return float(np.mean(err * err))


def _rmse(err, w, truth_w):
    return float(np.sqrt(np.mean(err * err)))


def _mae(err, w, truth_w):
    return float(np.mean(np.abs(err)))


def _grad(err, w, truth_w):
    return _weighted_mse(err, w if w is not None else truth_w())


def _sal(err, w, truth_w):
    if w is None:
        raise ValueError(
            "metric 'sal' needs weights= (the saliency map of the guide image, "
            "simlunar.features.feature_map('saliency', image))"
        )
    return _weighted_mse(err, w)


#: name -> ``fn(err, weights or None, truth_weights()) -> float`` over the evaluated cells
METRICS: dict[str, Callable] = {}
#: display names of the metrics (paper spelling), for tables and axis labels
METRIC_NAMES: dict[str, str] = {}
#: units of the metrics (GRAD and SAL are weighted mean squared errors), for axes and captions
METRIC_UNITS: dict[str, str] = {}


def register_metric(name: str, fn: Callable, *, label: str, unit: str) -> None:
    """Add a metric: its function (``fn(err, w, truth_w)``: the errors of the evaluated
    cells, their weights or None, and a callable giving the GRAD weights), display name and
    unit, declared once; every study kind scores it (``study.metrics``), tables and figures
    name it. A name registered twice is an error."""
    if name in METRICS:
        raise ValueError(f"metric {name!r} is registered twice")
    METRICS[name] = fn
    METRIC_NAMES[name] = label
    METRIC_UNITS[name] = unit


register_metric("mse", _mse, label="MSE", unit="m²")
register_metric("rmse", _rmse, label="RMSE", unit="m")
register_metric("mae", _mae, label="MAE", unit="m")
register_metric("grad", _grad, label="GRAD", unit="m²")
register_metric("sal", _sal, label="SAL", unit="m²")


def depth_gradient_weights(truth) -> np.ndarray:
    """GRAD weights: |grad truth| with ``numpy.gradient`` (float64, same shape)."""
    gy, gx = np.gradient(np.asarray(truth, dtype=np.float64))
    return np.hypot(gx, gy)


def metric(name: str, recon, truth, *, weights=None, mask=None) -> float:
    """Error of a reconstruction against ground truth.

    Parameters
    ----------
    name : str
        One of ``METRICS``.
    recon, truth : ndarray, shape (rows, cols)
        Reconstructed and true depth (same units, e.g. m). ``truth`` must be finite.
    weights : ndarray, shape (rows, cols), optional
        Per-cell weights >= 0 for ``grad`` (default |grad truth|) and ``sal`` (required).
    mask : ndarray of bool, shape (rows, cols), optional
        Cells to evaluate.

    Returns
    -------
    float
        The error (units of depth squared for the MSE family, depth for rmse/mae).
    """
    try:
        fn = METRICS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown metric {name!r}; valid: {', '.join(METRICS)}") from None
    recon = np.asarray(recon, dtype=np.float64)
    truth = np.asarray(truth, dtype=np.float64)
    if recon.shape != truth.shape or recon.ndim != 2:
        raise ValueError(f"recon {recon.shape} and truth {truth.shape} must be equal 2-D shapes")
    if not np.all(np.isfinite(truth)):
        raise ValueError("truth contains NaN or infinite values")
    keep = np.isfinite(recon)
    if mask is not None:
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != truth.shape:
            raise ValueError(f"mask shape {mask.shape} differs from truth {truth.shape}")
        keep &= mask
    if weights is not None:
        weights = np.asarray(weights, dtype=np.float64)
        if weights.shape != truth.shape:
            raise ValueError(f"weights shape {weights.shape} differs from truth {truth.shape}")
        if not np.all(np.isfinite(weights)) or weights.min() < 0:
            raise ValueError("weights must be finite and >= 0")
    if not keep.any():
        raise ValueError("no cell to evaluate (all masked or NaN)")
    if keep.all():
        err = (recon - truth).ravel()
        w = None if weights is None else weights.ravel()
        return fn(err, w, lambda: depth_gradient_weights(truth).ravel())
    err = recon[keep] - truth[keep]
    w = None if weights is None else weights[keep]
    return fn(err, w, lambda: depth_gradient_weights(truth)[keep])
