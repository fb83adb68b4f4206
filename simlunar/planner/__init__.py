"""Sample planners: which k pixels of the native grid a range sensor should measure."""

from simlunar.planner.combination import (
    CombinationFit,
    NelderMeadOptions,
    ScoreProtocol,
    fit_combination,
    score_combination,
)
from simlunar.planner.oracle import (
    ORACLES,
    framed_grid,
    hessian_norm,
    oracle_greedy,
    oracle_hessian,
)
from simlunar.planner.placement import (
    cvt_energy,
    density_from_map,
    halftone,
    lloyd,
    place,
    samples_per_cell,
)
from simlunar.planner.sequential import (
    MEASURING,
    SequentialOptions,
    SequentialPlan,
    plan_sequential,
)
from simlunar.planner.strategies import (
    PLACEMENTS,
    STRATEGIES,
    STRATEGY_NAMES,
    WEIGHTED,
    check_k,
    combine_maps,
    plan,
    strategy_options,
    strategy_weights,
)
from simlunar.planner.types import SamplePlan

__all__ = [
    "MEASURING",
    "ORACLES",
    "PLACEMENTS",
    "STRATEGIES",
    "STRATEGY_NAMES",
    "WEIGHTED",
    "CombinationFit",
    "NelderMeadOptions",
    "SamplePlan",
    "ScoreProtocol",
    "SequentialOptions",
    "SequentialPlan",
    "check_k",
    "combine_maps",
    "cvt_energy",
    "density_from_map",
    "fit_combination",
    "framed_grid",
    "halftone",
    "hessian_norm",
    "lloyd",
    "oracle_greedy",
    "oracle_hessian",
    "place",
    "plan",
    "plan_sequential",
    "samples_per_cell",
    "score_combination",
    "strategy_options",
    "strategy_weights",
]
