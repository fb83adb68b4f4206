"""Sample planners: which k pixels of the native grid a range sensor should measure."""

from simlunar.planner.combination import CombinationFit, fit_combination, score_combination
from simlunar.planner.strategies import (
    STRATEGIES,
    STRATEGY_NAMES,
    WEIGHTED,
    check_k,
    combine_maps,
    plan,
    strategy_weights,
)
from simlunar.planner.types import SamplePlan

__all__ = [
    "STRATEGIES",
    "STRATEGY_NAMES",
    "WEIGHTED",
    "CombinationFit",
    "SamplePlan",
    "check_k",
    "combine_maps",
    "fit_combination",
    "plan",
    "score_combination",
    "strategy_weights",
]
