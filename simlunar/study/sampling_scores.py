"""What the sampling study scores and how: every metric of one reconstruction in one pass.

A reconstruction is scored over the full image, the interior (cells farther than the sparsest
density's pitch from the border, :mod:`simlunar.metrics.interior`) or both; the interior scores
are named ``<metric>_interior``. The one-pass sums use the definitions of
:func:`simlunar.metrics.metric`; a metric they do not cover (any other entry of
:data:`simlunar.metrics.METRICS`) is computed by :func:`~simlunar.metrics.metric` itself.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from simlunar.features import feature_map
from simlunar.metrics import depth_gradient_weights, metric
from simlunar.metrics._fast import error_sums

__all__ = [
    "INTERIOR_SUFFIX",
    "SCORE_REGIONS",
    "SamplingEvaluator",
    "scored_metrics",
]


#: where a reconstruction is scored: the full image, the interior (cells farther than the
#: sparsest density's pitch from the border, :mod:`simlunar.metrics.interior`) or both
SCORE_REGIONS = ("full", "interior", "both")


#: metric name suffix of interior-only scores (``mse_interior``)
INTERIOR_SUFFIX = "_interior"


def scored_metrics(metrics: Sequence[str], region: str) -> list[str]:
    """Names of the scores a study reports: ``m`` (full image) and / or ``m_interior``."""
    full = list(metrics) if region in ("full", "both") else []
    inner = [m + INTERIOR_SUFFIX for m in metrics] if region in ("interior", "both") else []
    return full + inner


class SamplingEvaluator:
    """All metrics of one reconstruction in one pass (same definitions as ``metric``); metric
    weights computed once per study. With an interior mask, the same metrics on the interior
    cells (``<metric>_interior``) too or instead (``region``)."""

    def __init__(self, depth, image, metrics: list[str], maps_cache: dict, inner=None,
                 region: str = "full"):  # fmt: skip
        n = depth.size
        metric_w = {}
        if "grad" in metrics:
            metric_w["grad"] = depth_gradient_weights(depth).ravel()
        if "sal" in metrics:
            sal = maps_cache.get(("saliency", repr(None), repr(None)))
            metric_w["sal"] = (sal if sal is not None else feature_map("saliency", image)).ravel()
        for m, w in metric_w.items():
            if float(w.sum()) <= 0:
                raise ValueError(f"metric {m!r} weights are zero everywhere on this scene")
        self.truth = depth.ravel()
        self.metrics = metrics
        self.names = list(metric_w)
        self.rows = np.stack([metric_w[m] for m in self.names]) if self.names else np.zeros((0, n))
        self.region = region
        self.inner = None if inner is None else np.flatnonzero(np.asarray(inner).ravel())

    def warm(self) -> None:
        """Compile the one-pass kernel now (the protocol calls it before forking workers:
        a child then never enters Numba's dispatcher lock)."""
        error_sums(np.zeros(1), np.zeros(1), np.ones((self.rows.shape[0], 1)))

    def __call__(self, recon: np.ndarray, acquisition) -> dict[str, float]:
        flat = recon.ravel()
        out = {}
        if self.region in ("full", "both"):
            out.update(self._scores(flat, self.truth, self.rows, ""))
        if self.inner is not None:
            i = self.inner
            out.update(self._scores(flat[i], self.truth[i], self.rows[:, i], INTERIOR_SUFFIX))
        return out

    def _scores(self, recon, truth, rows, suffix: str) -> dict[str, float]:
        count, sse, sae, wse, wsum = error_sums(recon, truth, np.ascontiguousarray(rows))
        if count == 0:
            raise ValueError("reconstruction has no finite cell to evaluate")
        out = {}
        for m in self.metrics:
            if m == "mse":
                v = sse / count
            elif m == "rmse":
                v = float(np.sqrt(sse / count))
            elif m == "mae":
                v = sae / count
            elif m in self.names:
                j = self.names.index(m)
                if wsum[j] <= 0:
                    raise ValueError(f"metric {m!r} weights sum to zero over the evaluated cells")
                v = float(wse[j] / wsum[j])
            else:  # any other metric of METRICS: its own definition, on the same cells
                v = metric(m, recon[None, :], truth[None, :])
            out[m + suffix] = v
        return out
