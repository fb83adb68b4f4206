"""Cache keys that survive new options: keys at their "changes nothing" value are left out of the
study section (top level, inside each strategy's options, inside nested sections); any other value
stays, so a changed option still changes the key."""

from __future__ import annotations

import copy

from simlunar.results.cache_keys import (
    NEW_NESTED_DEFAULTS,
    NEW_PLANNER_DEFAULTS,
    NEW_STUDY_DEFAULTS,
    without_new_defaults,
)


def _opts(**over):
    base = {**copy.deepcopy(NEW_PLANNER_DEFAULTS), "uniform_mix": 0.0, "blue_noise": False}
    base["sequential"] = {**base["sequential"], **NEW_NESTED_DEFAULTS["sequential"]}
    base["feature_opts"] = {"wavelet": "db2", "model": None}
    return {**base, **over}


def test_a_study_written_before_the_new_keys_has_the_same_key():
    old = {"strategies": ["random", "w"], "strategy_options": {"w": {"uniform_mix": 0.0,
           "blue_noise": False, "feature_opts": {"wavelet": "db2"}}}}  # fmt: skip
    new = {**old, **NEW_STUDY_DEFAULTS, "strategy_options": {"w": _opts()}}
    assert without_new_defaults(new) == old
    assert without_new_defaults(old) == old


def test_a_changed_new_option_stays_in_the_key():
    study = {"score_region": "interior", "strategy_options": {
        "w": _opts(placement="lloyd", sequential={**_opts()["sequential"], "first_round": "prior"},
                   feature_opts={"model": "m.joblib"})}}  # fmt: skip
    out = without_new_defaults(study)
    assert out["score_region"] == "interior"
    w = out["strategy_options"]["w"]
    assert w["placement"] == "lloyd"
    # a section differing from the old defaults stays whole, the new key with it
    assert w["sequential"] == {**NEW_PLANNER_DEFAULTS["sequential"], "first_round": "prior"}
    assert w["feature_opts"] == {"model": "m.joblib"}


def test_the_lidar_studys_planner_options_too():
    study = {"planner_opts": {"grid": _opts()}, "options": {"planner_opts": {"w": _opts()},
             "other": 1}}  # fmt: skip
    out = without_new_defaults(study)
    expected = {"uniform_mix": 0.0, "blue_noise": False, "feature_opts": {"wavelet": "db2"}}
    assert out["planner_opts"] == {"grid": expected}
    assert out["options"] == {"planner_opts": {"w": expected}, "other": 1}


def test_the_input_is_not_modified_and_odd_values_pass_through():
    study = {"score_region": "full", "strategy_options": {"w": _opts(), "x": None}}
    before = copy.deepcopy(study)
    out = without_new_defaults(study)
    assert study == before
    assert out["strategy_options"]["x"] is None
    assert without_new_defaults({}) == {}
