"""Planner options of the schema, checked directly: which strategy takes which option (one message
per refusal), the placement-dependent default of uniform_mix, the feature-map options' own rules."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from pydantic import ValidationError

from simlunar.config import translate
from simlunar.config.loading import validate_data
from simlunar.config.planners import (
    CoefficientsCfg,
    FeatureOptsCfg,
    PlannerOptsCfg,
    SequentialCfg,
    StrategyOptionsCfg,
    check_planner_options,
    feature_keys,
)
from simlunar.errors import ConfigError
from simlunar.features import MAPS
from simlunar.planner import PLANNERS, plan, planner_label, planner_options, register_map_planner


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


def test_every_planner_option_is_a_yaml_key():
    # derived: every plan() option of every registered planner is a YAML key (or a section)
    fields = set(PlannerOptsCfg.model_fields)
    for name, entry in PLANNERS.items():
        keys = {entry.meta["section"]} if entry.meta.get("section") else set(planner_options(name))
        assert keys <= fields, name
    feature_fields = set(FeatureOptsCfg.model_fields)
    for name in MAPS:
        assert set(feature_keys(name)) <= feature_fields, name
    assert "density" not in feature_fields  # the learned map's density is the plan's k / N


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


def _experiment(study_extra: dict) -> dict:
    return {
        "name": "t",
        "seed": 1,
        "terrain": {"preset": "aerial_1", "scale": 0.125},
        "study": {"densities": ["1/8"], "trials": 1, "metrics": ["mse"], **study_extra},
    }


def test_unknown_planner_options_are_refused_with_did_you_mean():
    d = _experiment(
        {"strategies": ["wavelet"], "strategy_options": {"wavelet": {"blu_noise": True}}}
    )
    with pytest.raises(ConfigError, match=r"study.strategy_options.wavelet.blu_noise: .*"
                       r"\(did you mean 'blue_noise'\?\)$"):  # fmt: skip
        validate_data(d)
    d = _experiment(
        {"strategies": ["wavelet"], "strategy_options": {"wavelet": {"feature_opts": {"levls": 1}}}}
    )
    with pytest.raises(ConfigError, match=r"feature_opts.levls: .*\(did you mean 'levels'\?\)$"):
        validate_data(d)
    # a key of another placement: the placement it needs, from the placement registry
    d = _experiment(
        {"strategies": ["wavelet_lloyd"], "strategy_options": {"wavelet_lloyd": {"cap_block": 8}}}
    )
    with pytest.raises(ConfigError, match=r"cap_block: needs placement: random"):
        validate_data(d)


@dataclass(frozen=True)
class _RampOptions:
    """Options of the test's ramp map (none)."""


def _ramp(image) -> np.ndarray:
    """A map growing to the right: column index + 1."""
    g = np.asarray(image, dtype=np.float64)
    return np.broadcast_to(np.arange(1.0, g.shape[1] + 1.0), g.shape[:2]).copy()


@pytest.fixture
def ramp_planner():
    """A map and a planner on it registered by the test alone, removed afterwards."""
    MAPS.register("ramp", _ramp, _RampOptions, label="Ramp")
    register_map_planner("ramp_lloyd", "ramp", "lloyd")
    yield
    del PLANNERS._entries["ramp_lloyd"], MAPS._entries["ramp"]


def test_a_planner_registered_elsewhere_is_usable_from_yaml(ramp_planner):
    d = _experiment(
        {"strategies": ["ramp_lloyd"], "strategy_options": {"ramp_lloyd": {"lloyd_iterations": 3}}}
    )
    cfg = validate_data(d)
    kw = translate.strategy_options(cfg.study)["ramp_lloyd"]
    assert kw == {  # the Lloyd placement's options: its defaults, the YAML's iterations
        "density_power": None, "uniform_mix": 0.25, "lloyd_iterations": 3, "border_pitch": 0.75,
        "feature_opts": {},
    }  # fmt: skip
    assert planner_label("ramp_lloyd") == "Ramp, Lloyd"
    image = np.zeros((24, 32))
    p = plan("ramp_lloyd", 40, image=image, rng=0, **kw)
    # the Lloyd layout of the ramp's density (power 1/2, 25 % uniform): more samples on the right
    assert (p.cols >= 16).sum() > (p.cols < 16).sum()
    # the planner's own placement, unless the YAML names one: placement options follow it
    with pytest.raises(ConfigError, match=r"ramp_lloyd.blue_noise: needs placement: random"):
        validate_data(_experiment({
            "strategies": ["ramp_lloyd"], "strategy_options": {"ramp_lloyd": {"blue_noise": True}},
        }))  # fmt: skip


def test_a_planners_own_placement_keeps_explicit_defaults(ramp_planner):
    d = _experiment(
        {"strategies": ["ramp_lloyd"], "strategy_options": {"ramp_lloyd": {"uniform_mix": 0.0}}}
    )
    cfg = validate_data(d)
    opts = cfg.study.strategy_options["ramp_lloyd"]
    assert opts.placement == "lloyd"  # filled from the entry: the dump names it
    kw = translate.strategy_options(cfg.study)["ramp_lloyd"]
    assert kw["uniform_mix"] == 0.0 and "placement" not in kw  # the planner's own
