"""Sample planners: which k pixels of the native grid a range sensor should measure.

Every planner and placement is registered here once, with its options class
(:mod:`simlunar.planner.registry`); :func:`plan`, the YAML schema and the translation derive
from the entries. Every importance map of :data:`simlunar.features.MAPS` is a planner of its
own name (the paper's weighted random draw of it); a named variant is one line
(:func:`~simlunar.planner.registry.register_map_planner`).
"""

from simlunar.features import MAPS
from simlunar.planner.combination import (
    CombinationFit,
    NelderMeadOptions,
    ScoreProtocol,
    fit_combination,
    score_combination,
)
from simlunar.planner.draw import RandomDrawOptions, weighted_draw
from simlunar.planner.oracle import (
    ORACLES,
    OracleGreedyOptions,
    OracleHessianOptions,
    framed_grid,
    hessian_norm,
    oracle_greedy,
    oracle_hessian,
)
from simlunar.planner.placement import (
    LloydOptions,
    cvt_energy,
    density_from_map,
    halftone,
    lloyd,
    lloyd_layout,
    place,
    samples_per_cell,
)
from simlunar.planner.registry import (
    COMBINATION,
    PLACEMENTS,
    PLANNERS,
    MapSource,
    NoOptions,
    map_of,
    planner_label,
    planner_options,
    register_map_planner,
)
from simlunar.planner.sequential import (
    MEASURING,
    SequentialOptions,
    SequentialPlan,
    plan_sequential,
)
from simlunar.planner.strategies import (
    STRATEGIES,
    UniformLloydOptions,
    check_k,
    combine_maps,
    grid_planner,
    lloyd_uniform_planner,
    oracle_greedy_planner,
    oracle_hessian_planner,
    plan,
    random_planner,
    strategy_options,
    strategy_weights,
)
from simlunar.planner.types import SamplePlan

# ---- the registrations: one line per component --------------------------------------------
PLACEMENTS.register("random", weighted_draw, RandomDrawOptions, summary="the paper's weighted draw")
PLACEMENTS.register("lloyd", lloyd_layout, LloydOptions, summary="halftone + Lloyd")

PLANNERS.register("grid", grid_planner, NoOptions, label="Grid")
PLANNERS.register("random", random_planner, NoOptions, label="Random")
for _map in MAPS:  # every map is a planner of its own name: the paper's weighted draw of it
    register_map_planner(_map, _map)
register_map_planner("combination", COMBINATION, label="Combination")
register_map_planner("wavelet_lloyd", "wavelet", "lloyd")
register_map_planner("log_lloyd", "log_energy", "lloyd")
PLANNERS.register("lloyd_uniform", lloyd_uniform_planner, UniformLloydOptions,
                  label="Uniform Lloyd (no image)")  # fmt: skip
PLANNERS.register("oracle_greedy", oracle_greedy_planner, OracleGreedyOptions,
                  label="Oracle greedy (true error)", truth=True, section="oracle")  # fmt: skip
PLANNERS.register("oracle_hessian", oracle_hessian_planner, OracleHessianOptions,
                  label="Oracle Hessian (true depth)", truth=True)  # fmt: skip
PLANNERS.register("sequential", plan_sequential, SequentialOptions,
                  label="Sequential (multi-round)", measuring=True, section="sequential")  # fmt: skip

#: the strategies of the paper's section 4 (the sampling study's default), in its order
PAPER_STRATEGIES = ("grid", "random", "gradient", "entropy", "wavelet")
#: the recommended image-directed planner (the LIDAR and scanner studies' first planner; the
#: map of the figures' sample panels)
DEFAULT_PLANNER = "wavelet"
#: display names of the strategies (paper spelling), for tables and figure legends
STRATEGY_NAMES = {n: planner_label(n) for n in PLANNERS}

__all__ = [
    "COMBINATION",
    "DEFAULT_PLANNER",
    "MEASURING",
    "ORACLES",
    "PAPER_STRATEGIES",
    "PLACEMENTS",
    "PLANNERS",
    "STRATEGIES",
    "STRATEGY_NAMES",
    "CombinationFit",
    "LloydOptions",
    "MapSource",
    "NelderMeadOptions",
    "NoOptions",
    "OracleGreedyOptions",
    "OracleHessianOptions",
    "RandomDrawOptions",
    "SamplePlan",
    "ScoreProtocol",
    "SequentialOptions",
    "SequentialPlan",
    "UniformLloydOptions",
    "check_k",
    "combine_maps",
    "cvt_energy",
    "density_from_map",
    "fit_combination",
    "framed_grid",
    "halftone",
    "hessian_norm",
    "lloyd",
    "lloyd_layout",
    "map_of",
    "oracle_greedy",
    "oracle_hessian",
    "place",
    "plan",
    "plan_sequential",
    "planner_label",
    "planner_options",
    "register_map_planner",
    "samples_per_cell",
    "score_combination",
    "strategy_options",
    "strategy_weights",
]
