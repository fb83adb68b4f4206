"""Sample planners: which k pixels of the native grid a range sensor should measure."""

from simlunar.planner.strategies import (
    STRATEGIES,
    WEIGHTED,
    check_k,
    combine_maps,
    plan,
    strategy_weights,
)
from simlunar.planner.types import SamplePlan

__all__ = [
    "STRATEGIES",
    "WEIGHTED",
    "SamplePlan",
    "check_k",
    "combine_maps",
    "plan",
    "strategy_weights",
]
