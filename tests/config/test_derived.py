"""The YAML schema derived from a registry entry's options class, and study.reconstructions."""

from __future__ import annotations

from dataclasses import dataclass

import pytest
from pydantic import ValidationError

from simlunar.config.derived import (
    options_model,
    reconstruction_mapping,
    reconstruction_specs,
    validate_options,
)
from simlunar.config.studies import SamplingStudyCfg
from simlunar.reconstruction import RECONSTRUCTIONS, Reconstructed
from simlunar.registry import check_bounds, option


@dataclass(frozen=True)
class _Opts:
    """Options with every kind of rule."""

    weight: float = option(0.5, doc="image weight", unit="1", ge=0, le=1)
    sigma: float = option(2.0, doc="smoothing", unit="px", gt=0)
    iters: int = option(10, doc="iterations", ge=1, lt=100)
    mode: str = option("a", doc="mode", choices=("a", "b"))
    flag: bool = option(False, doc="a switch")

    def __post_init__(self):
        check_bounds(self)


def test_fields_types_defaults_bounds_and_docs_come_from_the_options_class():
    m = options_model(_Opts)
    assert list(m.model_fields) == ["weight", "sigma", "iters", "mode", "flag"]
    assert m().model_dump() == {
        "weight": 0.5,
        "sigma": 2.0,
        "iters": 10,
        "mode": "a",
        "flag": False,
    }
    assert m.model_fields["sigma"].description == "smoothing (px)"
    schema = m.model_json_schema()["properties"]
    assert schema["weight"]["minimum"] == 0 and schema["weight"]["maximum"] == 1
    assert schema["sigma"]["exclusiveMinimum"] == 0
    assert schema["iters"]["exclusiveMaximum"] == 100
    assert schema["mode"]["enum"] == ["a", "b"]


@pytest.mark.parametrize(
    "values, match",
    [
        ({"weight": 1.5}, "less than or equal to 1"),
        ({"weight": -0.1}, "greater than or equal to 0"),
        ({"sigma": 0.0}, "greater than 0"),
        ({"iters": 100}, "less than 100"),
        ({"mode": "c"}, "'a' or 'b'"),
        ({"weight": float("nan")}, "finite"),
        ({"iters": "many"}, "valid integer"),
    ],
)
def test_out_of_bounds_and_wrong_types_are_refused(values, match):
    with pytest.raises(ValidationError, match=match):
        validate_options(_Opts, values)


def test_a_stray_key_is_refused_with_the_valid_list_and_the_closest():
    with pytest.raises(ValidationError) as exc:
        validate_options(_Opts, {"sigmaa": 1.0}, name="reconstruction x")
    msg = str(exc.value)
    assert "unknown option 'sigmaa' of reconstruction x" in msg
    assert "valid: weight, sigma, iters, mode, flag" in msg and "did you mean 'sigma'" in msg


def test_validate_options_keeps_the_given_keys_only():
    assert validate_options(_Opts, {"sigma": 3}) == {"sigma": 3.0}
    assert validate_options(_Opts, None) == {}


def test_study_reconstructions_default_names_and_options():
    base = {"densities": [0.1]}
    assert SamplingStudyCfg(**base).reconstructions == ["linear"]
    assert SamplingStudyCfg(**base, reconstructions="linear").reconstructions == ["linear"]
    c = SamplingStudyCfg(**base, reconstructions=[{"linear": {"outside": "nan"}}])
    assert c.reconstructions == [{"linear": {"outside": "nan"}}]
    assert reconstruction_mapping(c.reconstructions) == {"linear": {"outside": "nan"}}
    # {name: {}} is the name: the default keeps one spelling (and the cache keys of before)
    assert reconstruction_specs([{"linear": {}}]) == ["linear"]


def test_a_reconstruction_under_a_label_of_its_own():
    c = SamplingStudyCfg(
        densities=[0.1],
        reconstructions=["linear", {"linear_nan": {"reconstruction": "linear", "outside": "nan"}}],
    )
    assert reconstruction_mapping(c.reconstructions) == {
        "linear": {},
        "linear_nan": {"reconstruction": "linear", "outside": "nan"},
    }
    with pytest.raises(ValidationError, match="label 'smoothed': a new name"):
        SamplingStudyCfg(
            densities=[0.1], reconstructions=[{"smoothed": {"reconstruction": "linear"}}]
        )
    with pytest.raises(ValidationError, match="unknown option 'outsid' of reconstruction x"):
        SamplingStudyCfg(
            densities=[0.1], reconstructions=[{"x": {"reconstruction": "linear", "outsid": 1}}]
        )


@pytest.mark.parametrize(
    "value, match",
    [
        (["lienar"], "unknown reconstruction 'lienar'; valid: linear"),
        ([{"linear": {"outsid": "nan"}}], "unknown option 'outsid' of reconstruction linear"),
        ([{"linear": {"outside": "far"}}], "'nearest' or 'nan'"),
        (["linear", "linear"], "listed twice"),
        ([{"linear": {}, "x": {}}], "one name or one"),
        ([], "non-empty"),
    ],
)
def test_study_reconstructions_errors(value, match):
    with pytest.raises(ValidationError, match=match):
        SamplingStudyCfg(densities=[0.1], reconstructions=value)


def test_a_registered_reconstruction_is_a_valid_yaml_name_at_once():
    def fn(points_rc, values, shape, *, guide=None, options=None):
        return Reconstructed(values)

    RECONSTRUCTIONS.register("test_derived", fn, _Opts, guided=True)
    try:
        c = SamplingStudyCfg(densities=[0.1], reconstructions=[{"test_derived": {"iters": 3}}])
        assert reconstruction_mapping(c.reconstructions) == {"test_derived": {"iters": 3}}
        with pytest.raises(ValidationError, match="greater than or equal to 1"):
            SamplingStudyCfg(densities=[0.1], reconstructions=[{"test_derived": {"iters": 0}}])
    finally:
        del RECONSTRUCTIONS._entries["test_derived"]
