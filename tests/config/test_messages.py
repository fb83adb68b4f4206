"""One-line validation messages (``<key.path>: <problem>``) on a small model tree: key paths
through sections, lists, ``kind`` unions and label mappings; valid keys of the right member."""

from __future__ import annotations

from typing import Literal

import pytest
from pydantic import Field, ValidationError, model_validator

from simlunar.config.fields import Density, Px, _Model, _tagged_union
from simlunar.config.messages import (
    format_validation_error,
    is_label_mapping,
    model_at,
    valid_keys,
    validate_file_data,
)
from simlunar.errors import ConfigError


class _Inner(_Model):
    spp: int = 4
    blur_px: Px = 0.0


class _A(_Model):
    kind: Literal["msg_a"] = "msg_a"
    x: float = 1.0


class _B(_Model):
    kind: Literal["msg_b"] = "msg_b"
    y: float = 1.0


class Root(_Model):
    seed: int
    render: _Inner = _Inner()
    light: _tagged_union("msg_a", _A, _B) = _A()
    opts: dict[str, _Inner] = Field(default_factory=dict)
    items: list[Density] = Field(default_factory=list)

    @model_validator(mode="after")
    def _even(self):
        if self.render.spp % 2:
            raise ValueError("render.spp: must be even")
        return self


def _line(data, prefix="", root=Root) -> str:
    with pytest.raises(ValidationError) as info:
        Root.model_validate(data)
    return format_validation_error(info.value, data, prefix, root=root)


@pytest.mark.parametrize(
    ("data", "line"),
    [
        (
            {"seed": 1, "render": {"spq": 8}},
            "render.spq: unknown key (valid keys: spp, blur_px) (did you mean 'spp'?)",
        ),
        (
            {"seed": 1, "light": {"kind": "msg_b", "x": 2}},
            "light.x: unknown key (valid keys: kind, y)",
        ),
        ({"seed": 1, "light": {"x": 2, "z": 0}}, "light.z: unknown key (valid keys: kind, x)"),
        ({"seed": 1, "light": {"kind": "moon"}}, "light: kind must be one of msg_a, msg_b"),
        ({"seed": 1, "items": [0.5, 2]}, "items[1]: a density must lie in (0, 1], got 2"),
        (
            {"seed": 1, "opts": {"fast": {"spp": "x"}}},
            "opts.fast.spp: Input should be a valid integer, unable to parse string as an integer",
        ),
        ({}, "seed: Field required"),
        # a misspelt key first, not the required key it leaves missing
        (
            {"sed": 1},
            "sed: unknown key (valid keys: seed, render, light, opts, items) (did you mean 'seed'?)",
        ),
        # a model validator naming a key inside the data: the path is that key's
        ({"seed": 1, "render": {"spp": 3}}, "render.spp: must be even"),
    ],
)
def test_one_line_per_error(data, line):
    assert _line(data) == line


def test_a_prefix_heads_the_path_and_no_root_no_hint():
    assert _line({"seed": 1, "render": {"spp": "x"}}, prefix="sweep[2]").startswith(
        "sweep[2].render.spp: Input should be a valid integer"
    )
    assert _line({"seed": 1, "render": {"spq": 8}}, root=None) == "render.spq: unknown key"


def test_model_at_follows_sections_unions_and_labels():
    assert model_at("", {}, Root) is Root
    assert model_at("render", {}, Root) is _Inner
    assert model_at("light", {"light": {"kind": "msg_b"}}, Root) is _B
    assert model_at("light", {}, Root) is _A  # no kind: the member with a default kind
    assert model_at("opts", {}, Root) is None  # free labels have no fixed keys
    assert model_at("opts.fast", {"opts": {"fast": {}}}, Root) is _Inner
    with pytest.raises(ConfigError, match=r"^render\.colour: no such key 'colour'$"):
        model_at("render.colour", {}, Root)


def test_valid_keys_and_label_mappings():
    assert valid_keys("light", {"light": {"kind": "msg_b"}}, Root) == ["kind", "y"]
    assert valid_keys("", {}, Root) == ["seed", "render", "light", "opts", "items"]
    assert valid_keys("opts", {}, Root) == []
    assert is_label_mapping("opts", {}, Root)
    assert not is_label_mapping("render", {}, Root)
    assert not is_label_mapping("nowhere.at_all", {}, Root)


def test_validate_file_data(tmp_path):
    f = tmp_path / "x.yaml"
    assert validate_file_data(Root, {"seed": 2}, f).seed == 2
    with pytest.raises(ConfigError) as info:
        validate_file_data(Root, {"seed": 2, "render": {"spq": 1}}, f)
    assert str(info.value) == (
        f"{f}: render.spq: unknown key (valid keys: spp, blur_px) (did you mean 'spp'?)"
    )
