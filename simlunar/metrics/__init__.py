"""Error metrics of a reconstruction and the paper's strategy score."""

from simlunar.metrics.errors import (
    METRIC_NAMES,
    METRIC_UNITS,
    METRICS,
    depth_gradient_weights,
    metric,
    register_metric,
)
from simlunar.metrics.interior import interior_mask, sparsest_pitch
from simlunar.metrics.score import check_densities, samples_for_equal_error, score

__all__ = [
    "METRICS",
    "METRIC_NAMES",
    "METRIC_UNITS",
    "check_densities",
    "depth_gradient_weights",
    "interior_mask",
    "metric",
    "register_metric",
    "samples_for_equal_error",
    "score",
    "sparsest_pitch",
]
