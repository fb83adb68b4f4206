"""YAML blocks derived from options classes: a key's name, unit, default, bounds and doc come
from the field's declaration; the block turns a config back into the library's keywords; the
library's rules across fields fail at load; every LIDAR block agrees with the library."""

from __future__ import annotations

import math
from dataclasses import dataclass

import pytest
from pydantic import ValidationError

from simlunar.config.lidar import BLOCKS
from simlunar.config.option_blocks import KEY_UNITS, Block, Part, key_name
from simlunar.registry import Options, option


@dataclass(frozen=True)
class _Probe(Options):
    """A probe of the derivation."""

    width_s: float = option(2e-9, doc="a width", unit="s", key_unit="ns", ge=0, le=1e-5)
    energy_j: float = option(1e-5, doc="an energy", unit="J", key_unit="uJ", gt=0)
    angle_rad: float = option(1e-3, doc="an angle", unit="rad", key_unit="mrad", lt=math.pi / 2)
    power: float = option(1.0, doc="a power", unit="W/sr", key_unit="W/sr", gt=0)
    count: int = option(3, doc="a count", ge=1)
    mode: str = option("a", doc="a mode", choices=("a", "b"))
    low_m: float = option(0.0, doc="low", unit="m")
    high_m: float = option(1.0, doc="high", unit="m")

    def __post_init__(self):
        super().__post_init__()
        if not self.low_m < self.high_m:
            raise ValueError(f"low_m must be < high_m, got {self.low_m} >= {self.high_m}")


PROBE = Block("ProbeCfg", "probe", (Part("probe", _Probe, rename={"count": "n"}),))


def test_key_names_carry_the_key_unit():
    assert list(PROBE.model.model_fields) == [
        "width_ns", "energy_uj", "angle_mrad", "power_w_sr", "n", "mode", "low_m", "high_m",
    ]  # fmt: skip
    assert key_name("fwhm_s", {"unit": "s", "key_unit": "ns"}) == "fwhm_ns"
    assert key_name("laser_intensity", {"unit": "W/sr", "key_unit": "W/sr"}) == (
        "laser_intensity_w_sr"
    )
    assert key_name("gain", {"unit": None, "key_unit": None}) == "gain"


def test_defaults_and_bounds_are_converted_to_the_key_unit():
    f = PROBE.model.model_fields
    # 2e-9 s in ns is 2 (not 2.0000000000000004), the bound 1e-5 s is 10 000 ns
    assert f["width_ns"].default == 2.0 and f["energy_uj"].default == 10.0
    assert [repr(m) for m in f["width_ns"].metadata] == ["Ge(ge=0.0)", "Le(le=10000.0)"]
    assert f["width_ns"].description == "a width (ns)"
    with pytest.raises(ValidationError, match="less than or equal to 10000"):
        PROBE.model(width_ns=10001)
    with pytest.raises(ValidationError, match=r"less than 1570\.79"):
        PROBE.model(angle_mrad=1571)
    with pytest.raises(ValidationError, match="Input should be 'a' or 'b'"):
        PROBE.model(mode="c")
    # a length takes an explicit unit
    assert PROBE.model(high_m="20 cm").high_m == pytest.approx(0.2)


def test_the_library_keywords_in_si_units_by_the_same_factors():
    cfg = PROBE.model(width_ns=4, energy_uj=10, angle_mrad=2, n=5)
    kw = PROBE.library(cfg, "probe")
    # the same products the hand-written translation computed (4 * 1e-9, not 4 / 1e9)
    assert kw["width_s"] == 4 * 1e-9 and kw["energy_j"] == 10 * 1e-6
    assert kw["angle_rad"] == 2 * 1e-3 and kw["count"] == 5 and kw["power"] == 1.0
    assert PROBE.options(cfg) == _Probe(width_s=4 * 1e-9, energy_j=10 * 1e-6, angle_rad=2e-3,
                                        count=5)  # fmt: skip


def test_a_rule_across_fields_fails_at_load():
    with pytest.raises(ValidationError, match="low_m must be < high_m"):
        PROBE.model(low_m=2.0)


def test_a_stray_key_names_the_closest():
    with pytest.raises(ValidationError, match="Extra inputs are not permitted"):
        PROBE.model(width_n=3)


def test_a_key_unit_that_is_no_multiple_of_the_unit_is_refused():
    @dataclass(frozen=True)
    class Bad(Options):
        t_s: float = option(1.0, doc="t", unit="s", key_unit="mm")

    with pytest.raises(ValueError, match="key unit 'mm' is no multiple of 's'"):
        Block("BadCfg", "bad", (Part("bad", Bad),))
    assert KEY_UNITS["mm"] == ("m", 1e-3)


def _library_bounds(block: Block, key: str):
    k = block.keys[key]
    cls = block.parts[k.part].options
    meta = {f.name: f.metadata for f in cls.__dataclass_fields__.values()}[k.field]
    return cls, k, {b: meta.get(b) for b in ("ge", "gt", "le", "lt") if meta.get(b) is not None}


@pytest.mark.parametrize("name", sorted(BLOCKS))
def test_every_lidar_key_refuses_what_its_library_field_refuses(name):
    # the bounds are written once: a YAML value just past a bound is refused by the schema,
    # and its SI value by the options class (a hand-written bound on either side would drift)
    block = BLOCKS[name]
    checked = 0
    for key in block.keys:
        cls, k, bounds = _library_bounds(block, key)
        if k.nested is not None or k.width_height:
            continue
        for b, bound in bounds.items():
            past = bound - abs(bound) * 1e-3 - 1e-9 if b in ("ge", "gt") else bound * 1.001 + 1e-9
            if b == "gt":
                past = bound
            if b == "lt":
                past = bound
            with pytest.raises(ValidationError):
                block.model(**{key: past / k.factor})
            with pytest.raises(ValueError):
                cls(**{k.field: past})
            checked += 1
    assert checked > 0 or name in ("motion",)


@pytest.mark.parametrize("name", sorted(BLOCKS))
def test_every_lidar_default_is_the_library_s(name):
    block = BLOCKS[name]
    cfg = block.model()
    for key, k in block.keys.items():
        value = getattr(cfg, key)
        if value is None or k.nested is not None:
            continue  # null: the library's default or the instrument's
        lib = getattr(block.parts[k.part].options(), k.field)
        assert k.to_library(value) == pytest.approx(lib), key
