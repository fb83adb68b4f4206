"""Sampling-study metrics of a reconstructed guide-view depth against a ground truth with holes.

The truth of a scanned view has holes (cells no projector ray lights, or that the camera does not
see); they are left out of every metric and of the ``grad`` weights, which use differences between
valid truth cells only (as ``numpy.gradient`` elsewhere), so the zero put into a hole never makes
the cells next to it the steepest of the image. Metric definitions: :func:`simlunar.metrics.metric`.
"""

from __future__ import annotations

import numpy as np

from simlunar.features import feature_map
from simlunar.metrics import metric

__all__ = [
    "score_depth",
]


def _gradient_weights_with_holes(truth: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """GRAD weights |grad truth| with the holes of ``truth`` (``~valid``) left out.

    As ``numpy.gradient``: central differences, one-sided at the border and, here, next to a
    hole; 0 in the holes and where a cell has no valid neighbour along an axis.
    """
    t = np.where(valid, truth, 0.0)
    grads = []
    for axis in (0, 1):
        d = np.diff(t, axis=axis)
        ok = np.diff(valid.astype(np.int8), axis=axis) == 0
        ok &= np.delete(valid, 0, axis=axis)  # both ends of each difference valid
        d = np.where(ok, d, 0.0)
        pad = [(0, 0), (0, 0)]
        pad[axis] = (1, 0)
        minus, ok_m = np.pad(d, pad), np.pad(ok, pad)  # difference to the previous cell
        pad[axis] = (0, 1)
        plus, ok_p = np.pad(d, pad), np.pad(ok, pad)  # difference to the next cell
        n = ok_m.astype(float) + ok_p
        grads.append(np.where(n > 0, (minus + plus) / np.maximum(n, 1), 0.0))
    return np.where(valid, np.hypot(*grads), 0.0)


def score_depth(
    depth: np.ndarray, truth: np.ndarray, *, metrics, image=None, mask=None
) -> dict[str, float]:
    """Sampling-study metrics of a reconstructed guide-view depth against ground truth.

    Parameters
    ----------
    depth, truth : (H, W) float64 z-depth (m); NaN in ``truth`` is excluded (also from the
        ``grad`` weights, which use differences between finite truth cells only)
    metrics : names from :data:`simlunar.metrics.METRICS` (``sal`` uses the saliency map of
        ``image`` as weights)
    image : (H, W) guide image (needed for ``sal``)
    mask : (H, W) bool, optional extra evaluation mask
    """
    valid = np.isfinite(truth)
    if mask is not None:
        valid &= np.asarray(mask, bool)
    t = np.where(valid, truth, 0.0)
    out = {}
    for name in metrics:
        weights = None
        if name == "grad":
            # |grad truth| from differences between valid cells only: the 0 put into the
            # holes must not make the cells next to them the steepest of the image
            weights = _gradient_weights_with_holes(truth, np.isfinite(truth))
        if name == "sal":
            if image is None:
                raise ValueError("metric 'sal' needs the guide image for its saliency weights")
            weights = feature_map("saliency", image)
        out[name] = float(metric(name, depth, t, weights=weights, mask=valid))
    return out
