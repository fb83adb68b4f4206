"""The schema's field types and base models: units converted once, whole pixel counts, finite
numbers only, unknown keys refused, overrides that serialise only what they set, ``kind`` unions."""

from __future__ import annotations

import math
from typing import Literal

import pytest
from pydantic import ValidationError

from simlunar.config.fields import (
    Deg,
    Density,
    Metres,
    Px,
    PxCount,
    _Model,
    _partial,
    _tagged_union,
    unique_names,
)


class Probe(_Model):
    angle_deg: Deg = 0.0
    length_m: Metres = 0.0
    density: Density = 1.0
    blur_px: Px = 0.0
    width_px: PxCount = 1


def _error(**kw) -> str:
    with pytest.raises(ValidationError) as info:
        Probe(**kw)
    errors = info.value.errors()
    assert len(errors) == 1, errors
    return errors[0]["msg"]


@pytest.mark.parametrize(
    ("kw", "field", "expected"),
    [
        ({"angle_deg": 30}, "angle_deg", 30.0),
        ({"angle_deg": "0.5 rad"}, "angle_deg", math.degrees(0.5)),
        ({"angle_deg": "45 degrees"}, "angle_deg", 45.0),
        ({"length_m": "20 cm"}, "length_m", 0.2),
        ({"length_m": "1.5 km"}, "length_m", 1500.0),
        ({"length_m": "3"}, "length_m", 3.0),
        ({"density": "1/2048"}, "density", 1 / 2048),
        ({"density": 0.25}, "density", 0.25),
        ({"blur_px": "1.5 px"}, "blur_px", 1.5),
        ({"width_px": "256 px"}, "width_px", 256),
        ({"width_px": 64}, "width_px", 64),
    ],
)
def test_values_are_converted_into_the_keys_unit(kw, field, expected):
    assert getattr(Probe(**kw), field) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"angle_deg": "30 m"}, "bad unit 'm' for a _deg key (valid units: deg, degree, degrees"),
        ({"length_m": "20 deg"}, "bad unit 'deg' for a _m key"),
        ({"density": "3/2"}, "a density must lie in (0, 1], got '3/2'"),
        ({"density": "1/0"}, "expected a fraction like 1/2 or a number, got '1/0'"),
        ({"blur_px": -1}, "greater than or equal to 0"),
        ({"width_px": "2.5 px"}, "expected a whole number of pixels, got '2.5 px'"),
        ({"width_px": 0}, "greater than 0"),
        ({"angle_deg": float("inf")}, "expected a finite number, got inf"),
        ({"colour": "red"}, "Extra inputs are not permitted"),
    ],
)
def test_bad_values_are_refused_with_their_reason(kw, message):
    assert message in _error(**kw)


def test_models_are_frozen():
    p = Probe()
    with pytest.raises(ValidationError, match="frozen"):
        p.angle_deg = 3.0


def test_unique_names():
    assert unique_names(["grid", "random"]) == ["grid", "random"]
    with pytest.raises(ValueError, match=r"^names must be unique, got \['grid', 'grid'\]$"):
        unique_names(["grid", "grid"])


def test_a_partial_model_keeps_unset_keys_out_of_its_dump():
    Over = _partial(Probe)
    assert Over.__name__ == "ProbeOverride"
    o = Over(length_m="50 cm")
    assert o.length_m == 0.5 and o.angle_deg is None
    assert o.model_dump() == {"length_m": 0.5}  # an override names only what it changes
    assert Over().model_dump() == {}
    with pytest.raises(ValidationError, match="Extra inputs are not permitted"):
        Over(colour="red")
    with pytest.raises(ValidationError, match="a density must lie in"):
        Over(density=2)  # the field's own check still applies


class Sun(_Model):
    kind: Literal["probe_sun"] = "probe_sun"
    elevation_deg: Deg = 30.0


class Lamp(_Model):
    kind: Literal["probe_lamp"] = "probe_lamp"
    power: float = 1.0


class Holder(_Model):
    light: _tagged_union("probe_sun", Sun, Lamp) = Sun()


def test_a_tagged_union_is_chosen_by_kind_with_a_default():
    assert isinstance(Holder(light={"elevation_deg": "0.5 rad"}).light, Sun)  # no kind: the default
    assert isinstance(Holder(light={"kind": "probe_lamp", "power": 2}).light, Lamp)
    with pytest.raises(ValidationError) as info:
        Holder(light={"kind": "moon"})
    assert info.value.errors()[0]["msg"] == "kind must be one of probe_sun, probe_lamp"
    with pytest.raises(ValidationError, match="Extra inputs are not permitted"):
        Holder(light={"kind": "probe_lamp", "elevation_deg": 3})  # a key of the other member
