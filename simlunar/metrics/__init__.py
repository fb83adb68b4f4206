"""Error metrics of a reconstruction and the paper's strategy score."""

from simlunar.metrics.errors import METRIC_NAMES, METRICS, depth_gradient_weights, metric
from simlunar.metrics.interior import interior_mask, sparsest_pitch
from simlunar.metrics.score import check_densities, samples_for_equal_error, score

__all__ = [
    "METRICS",
    "METRIC_NAMES",
    "check_densities",
    "depth_gradient_weights",
    "interior_mask",
    "metric",
    "samples_for_equal_error",
    "score",
    "sparsest_pitch",
]
