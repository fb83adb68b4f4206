"""Planner options of the schema, checked directly: which strategy takes which option (one message
per refusal), the placement-dependent default of uniform_mix, the feature-map options' own rules."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from simlunar.config.planners import (
    FEATURE_OPTION_KEYS,
    STRATEGY_OPTION_KEYS,
    CoefficientsCfg,
    FeatureOptsCfg,
    PlannerOptsCfg,
    SequentialCfg,
    StrategyOptionsCfg,
    check_planner_options,
)


def _refusal(base: str, **opts) -> str:
    with pytest.raises(ValueError) as info:
        check_planner_options(base, PlannerOptsCfg(**opts))
    return str(info.value)


def test_uniform_mix_defaults_by_placement():
    assert PlannerOptsCfg().uniform_mix == 0.0
    assert PlannerOptsCfg(placement="lloyd").uniform_mix == 0.25
    assert PlannerOptsCfg(placement="lloyd", uniform_mix=0.0).uniform_mix == 0.0
    assert StrategyOptionsCfg(placement="lloyd").uniform_mix == 0.25
    assert StrategyOptionsCfg().strategy is None


@pytest.mark.parametrize(
    ("base", "opts"),
    [
        ("grid", {}),
        ("random", {}),
        ("lloyd_uniform", {"lloyd_iterations": 5, "border_pitch": None}),
        ("oracle_greedy", {"oracle": {"start_share": 0.5}}),
        ("oracle_hessian", {"density_power": 0.5, "uniform_mix": 0.1}),
        ("sequential", {"sequential": {"prior": "wavelet"}, "feature_opts": {"levels": 2}}),
        ("wavelet", {"feature_opts": {"wavelet": "haar", "levels": 3}}),
        ("entropy", {"placement": "lloyd", "feature_opts": {"size": 5}}),
        ("gradient", {"density_cap": 4.0, "blue_noise": True}),
        ("combination", {"coefficients": {"wavelet": 1, "entropy": 2},
                         "feature_opts": {"size": 3, "levels": 1}}),
    ],
)  # fmt: skip
def test_options_a_strategy_takes_are_accepted(base, opts):
    check_planner_options(base, PlannerOptsCfg(**opts))


@pytest.mark.parametrize(
    ("base", "opts", "message"),
    [
        ("grid", {"placement": "lloyd"}, "placement: strategy 'grid' takes no options"),
        ("random", {"density_power": 2.0}, "density_power: strategy 'random' takes no options"),
        ("lloyd_uniform", {"blue_noise": True},
         "blue_noise: not an option of strategy 'lloyd_uniform' "
         "(valid: lloyd_iterations, border_pitch)"),
        ("wavelet", {"oracle": {"nms_pitch": 2.0}},
         "oracle: only the oracle_greedy strategy takes it ('wavelet')"),
        ("gradient", {"sequential": {"max_rounds": 3}},
         "sequential: only the sequential strategy takes it ('gradient')"),
        ("gradient", {"placement": "lloyd", "cap_block": 8},
         "cap_block: needs placement: random (strategy 'gradient')"),
        ("saliency", {"border_pitch": 0.0},
         "border_pitch: needs placement: lloyd (strategy 'saliency')"),
        ("combination", {}, "coefficients: strategy 'combination' needs at least one weight"),
        ("wavelet", {"coefficients": {"wavelet": 1.0}},
         "coefficients: only the combination strategy takes them ('wavelet')"),
        ("gradient", {"feature_opts": {"levels": 2}},
         "feature_opts.levels: not an option of the gradient map (valid: none)"),
        ("entropy", {"feature_opts": {"wavelet": "haar"}},
         "feature_opts.wavelet: not an option of the entropy map (valid: scale, size)"),
        ("combination", {"coefficients": {"gradient": 1.0, "entropy": 1.0},
                         "feature_opts": {"boundary": "periodic"}},
         "feature_opts.boundary: not an option of the gradient/entropy map (valid: scale, size)"),
        ("sequential", {"feature_opts": {"levels": 2}},
         "feature_opts.levels: not an option of the no map (valid: none)"),
        ("learned", {}, "feature_opts.model: the learned map needs its model file (.joblib)"),
    ],
)  # fmt: skip
def test_options_a_strategy_does_not_take_are_refused(base, opts, message):
    assert _refusal(base, **opts) == message


def test_every_strategy_option_key_is_a_planner_option():
    fields = set(PlannerOptsCfg.model_fields)
    for base, keys in STRATEGY_OPTION_KEYS.items():
        assert set(keys) <= fields, base
    feature_fields = set(FeatureOptsCfg.model_fields)
    for name, keys in FEATURE_OPTION_KEYS.items():
        assert set(keys) <= feature_fields, name


@pytest.mark.parametrize(
    ("opts", "message"),
    [
        ({"model": "m.pkl"}, "a learned model file ends in .joblib, got 'm.pkl'"),
        ({"size": 8}, "entropy window size must be odd, 1..63, got 8"),
        ({"size": 65}, "entropy window size must be odd, 1..63, got 65"),
        ({"wavelet": "db99"}, "unknown discrete wavelet 'db99' (e.g. db2, haar, sym4)"),
        ({"boundary": "zero"}, "Input should be 'symmetric' or 'periodic'"),
    ],
)
def test_feature_options_follow_the_maps_own_rules(opts, message):
    with pytest.raises(ValidationError) as info:
        FeatureOptsCfg(**opts)
    assert message in info.value.errors()[0]["msg"]


def test_coefficients_and_the_sequential_rules():
    assert CoefficientsCfg(wavelet=0.5, uniform=0).as_mapping() == {"uniform": 0, "wavelet": 0.5}
    assert CoefficientsCfg().as_mapping() == {}
    with pytest.raises(ValidationError, match="greater than or equal to 0"):
        CoefficientsCfg(gradient=-1)
    assert SequentialCfg(first_round="prior", prior="entropy").first_round == "prior"
    with pytest.raises(ValidationError, match=r"first_round: 'prior' needs a prior map"):
        SequentialCfg(first_round="prior")
    with pytest.raises(ValidationError, match="greater than or equal to 2"):
        SequentialCfg(max_rounds=1)
