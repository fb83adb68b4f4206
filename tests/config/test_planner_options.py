"""Lloyd-placement planners in the YAML: placement, oracles, sequential, learned, score_region."""

from __future__ import annotations

import inspect
import json
from dataclasses import asdict

import pytest

from simlunar.config import studies, translate
from simlunar.config.loading import validate_data
from simlunar.errors import ConfigError
from simlunar.pipeline.runner import unit_key
from simlunar.planner import (
    LloydOptions,
    OracleGreedyOptions,
    SequentialOptions,
    placement,
)
from simlunar.results.cache_keys import (
    NEW_NESTED_DEFAULTS,
    NEW_PLANNER_DEFAULTS,
    NEW_STUDY_DEFAULTS,
)


def base(**study) -> dict:
    s = {"strategies": ["random", "grid"], "densities": [0.5, 0.25]}
    s.update(study)
    return {"name": "t", "seed": 1, "terrain": {"preset": "aerial_1", "scale": 0.125}, "study": s}


def error_of(data) -> str:
    with pytest.raises(ConfigError) as info:
        validate_data(data)
    msg = str(info.value)
    assert "\n" not in msg
    return msg


def _defaults(fn) -> dict:
    return {
        k: p.default
        for k, p in inspect.signature(fn).parameters.items()
        if p.default is not inspect.Parameter.empty
    }


def test_lloyd_defaults_are_the_library_defaults():
    kw = translate.planner_kwargs("wavelet", studies.PlannerOptsCfg(placement="lloyd"))
    lib, place = LloydOptions(), _defaults(placement.place)
    assert (
        kw["uniform_mix"] == lib.uniform_mix == 0.25 == _defaults(placement.density_from_map)["mix"]
    )
    assert kw["lloyd_iterations"] == lib.lloyd_iterations == place["iterations"]
    assert kw["border_pitch"] == lib.border_pitch == place["border"]
    assert kw["density_power"] is None  # the library's placement default (1/2 for lloyd)
    assert "blue_noise" not in kw and kw["placement"] == "lloyd"
    # random placement: exactly the keys of before (same numbers, same cache keys)
    assert "placement" not in translate.planner_kwargs("wavelet", studies.PlannerOptsCfg())


def test_oracle_and_sequential_defaults_are_the_library_defaults():
    # the YAML's oracle section is the library's options class (the oracles read their
    # options, with no defaults of their own to keep in step)
    assert studies.PlannerOptsCfg().oracle.model_dump() == asdict(OracleGreedyOptions())
    # options the YAML leaves out are the library's own (the oracle's density defaults)
    assert translate.planner_kwargs("oracle_hessian", studies.PlannerOptsCfg()) == {}
    set_ = studies.PlannerOptsCfg(uniform_mix=0.1, density_power=None)
    assert translate.planner_kwargs("oracle_hessian", set_) == {"uniform_mix": 0.1}
    seq = translate.planner_kwargs("sequential", studies.PlannerOptsCfg())
    assert seq["sequential"] == SequentialOptions() and seq["prior"] is None
    # the cache-key tables hold the schema's defaults
    d = studies.PlannerOptsCfg().model_dump(mode="json")
    tables = {k: {**v, **NEW_NESTED_DEFAULTS.get(k, {})} if isinstance(v, dict) else v
              for k, v in NEW_PLANNER_DEFAULTS.items()}  # fmt: skip
    assert {k: d[k] for k in NEW_PLANNER_DEFAULTS} == tables
    s = studies.SamplingStudyCfg(densities=[0.5]).model_dump(mode="json")
    assert {k: s[k] for k in NEW_STUDY_DEFAULTS} == NEW_STUDY_DEFAULTS
    assert asdict(SequentialOptions()).items() <= studies.SequentialCfg().model_dump().items()


@pytest.mark.parametrize(
    ("study", "message"),
    [
        (
            {"strategies": ["random", "w"], "strategy_options": {"w": {"strategy": "wavelet",
                                                                       "placement": "halftone"}}},
            "study.strategy_options.w.placement: ",
        ),
        (
            {"strategies": ["random", "w"], "strategy_options": {"w": {"strategy": "wavelet",
                                                                       "placement": "lloyd",
                                                                       "blue_noise": True}}},
            "study.strategy_options.w.blue_noise: needs placement: random",
        ),
        (
            {"strategies": ["random", "wavelet"],
             "strategy_options": {"wavelet": {"lloyd_iterations": 5}}},
            "study.strategy_options.wavelet.lloyd_iterations: needs placement: lloyd",
        ),
        (
            {"strategies": ["random", "s"],
             "strategy_options": {"s": {"strategy": "sequential",
                                        "sequential": {"first_round": "prior"}}}},
            "study.strategy_options.s.sequential.first_round: 'prior' needs a prior map",
        ),
        (
            {"strategies": ["random", "oracle_magic"]},
            "study.strategies[1]: unknown strategy 'oracle_magic'",
        ),
        (
            {"strategies": ["random", "bound"],
             "strategy_options": {"bound": {"strategy": "oracle_greedy"}}},
            "study.strategy_options.bound: a label of an oracle",
        ),
        (
            {"strategies": ["random", "oracle_greedy"],
             "strategy_options": {"oracle_greedy": {"placement": "lloyd"}}},
            "study.strategy_options.oracle_greedy.placement: not an option of strategy",
        ),
        (
            {"strategies": ["random", "wavelet"],
             "strategy_options": {"wavelet": {"sequential": {"max_rounds": 3}}}},
            "study.strategy_options.wavelet.sequential: only the sequential strategy",
        ),
        (
            {"strategies": ["random", "sequential"],
             "strategy_options": {"sequential": {"sequential": {"first_share": 1.5}}}},
            "study.strategy_options.sequential.sequential.first_share: ",
        ),
        (
            {"strategies": ["random", "learned"]},
            "study: strategies (learned).feature_opts.model: the learned map needs its model",
        ),
        ({"score_region": "edges"}, "study.score_region: "),
    ],
)  # fmt: skip
def test_bad_planner_options_are_one_line_errors_with_the_key_path(study, message):
    assert error_of(base(**study)).startswith(message)


def test_oracles_and_sequential_are_not_scanner_planners():
    data = {
        "name": "t",
        "seed": 1,
        "terrain": {"preset": "moonyard", "scale": 0.0625},
        "study": {"kind": "scanner", "planners": ["oracle_greedy"]},
    }
    assert error_of(data).startswith("study.planners[0]: 'oracle_greedy' is a planner of the")


def test_new_options_parse_and_translate():
    cfg = validate_data(
        base(
            strategies=["random", "lloyd_uniform", "wl", "seq", "oracle_greedy"],
            strategy_options={
                "wl": {"strategy": "wavelet", "placement": "lloyd", "density_power": 0.7},
                "seq": {"strategy": "sequential", "sequential": {"prior": "wavelet",
                                                                 "max_rounds": 4}},
                "oracle_greedy": {"oracle": {"batch_share": 0.3}},
            },
            score_region="both",
        )
    )  # fmt: skip
    o = translate.sampling_options(cfg.study)
    assert o.score_region == "both"
    assert o.strategy_options["wl"]["density_power"] == 0.7
    assert o.strategy_options["seq"]["sequential"].max_rounds == 4
    assert o.strategy_options["seq"]["prior"] == "wavelet"
    assert o.strategy_options["oracle_greedy"]["batch_share"] == 0.3


def test_cache_keys_of_runs_without_the_new_options_are_unchanged():
    plain = base(strategy_options={}, strategies=["random", "wavelet_bn"])
    plain["study"]["strategy_options"] = {"wavelet_bn": {"strategy": "wavelet", "blue_noise": True}}
    cfg = validate_data(plain)
    dumped = cfg.model_dump(mode="json", by_alias=True)
    old = {**dumped, "study": {k: v for k, v in dumped["study"].items() if k != "score_region"}}
    opts = old["study"]["strategy_options"]["wavelet_bn"]
    opts = {k: v for k, v in opts.items() if k not in NEW_PLANNER_DEFAULTS}
    opts["feature_opts"] = {k: v for k, v in opts["feature_opts"].items() if k != "model"}
    old["study"]["strategy_options"] = {"wavelet_bn": opts}
    assert unit_key(dumped, {}) == unit_key(old, {})
    lloyd = validate_data(
        base(strategies=["random", "w"],
             strategy_options={"w": {"strategy": "wavelet", "placement": "lloyd"}})
    ).model_dump(mode="json", by_alias=True)  # fmt: skip
    assert unit_key(lloyd, {}) != unit_key(dumped, {})
    # a key added inside the sequential section (first_round) leaves keys of before unchanged
    seq = validate_data(
        base(strategies=["random", "s"],
             strategy_options={"s": {"strategy": "sequential", "sequential": {"prior": "wavelet"}}})
    ).model_dump(mode="json", by_alias=True)  # fmt: skip
    before = json.loads(json.dumps(seq))
    del before["study"]["strategy_options"]["s"]["sequential"]["first_round"]
    assert unit_key(seq, {}) == unit_key(before, {})
    seq["study"]["strategy_options"]["s"]["sequential"]["first_round"] = "prior"
    assert unit_key(seq, {}) != unit_key(before, {})
