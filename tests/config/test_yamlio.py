"""YAML in: duplicate keys refused with both lines, merge keys allowed, aliases bounded, one-line
errors naming the file; ``--set`` values parsed as YAML; ``dump_yaml`` round trips in key order."""

from __future__ import annotations

import pytest
import yaml

from simlunar.config import yamlio
from simlunar.config.yamlio import (
    MAX_YAML_NODES,
    dump_yaml,
    load_yaml,
    parse_set,
    safe_load_bounded,
    safe_load_text,
)
from simlunar.errors import ConfigError


def test_a_duplicate_key_names_both_lines():
    with pytest.raises(yaml.YAMLError) as info:
        safe_load_bounded("a: 1\nb: 2\na: 3\n")
    assert info.value.problem == "duplicate key 'a' (first at line 1)"
    assert info.value.problem_mark.line == 2
    # the same key in two different mappings is fine
    assert safe_load_bounded("x: {a: 1}\ny: {a: 2}\n") == {"x": {"a": 1}, "y": {"a": 2}}


def test_merge_keys_may_be_overridden_but_explicit_keys_not_repeated():
    text = "base: &b {scale: 0.1, preset: aerial_1}\nt: {<<: *b, scale: 0.5}\n"
    assert safe_load_bounded(text)["t"] == {"scale": 0.5, "preset": "aerial_1"}
    with pytest.raises(yaml.YAMLError, match="duplicate key 'scale'"):
        safe_load_bounded("base: &b {preset: a}\nt: {<<: *b, scale: 0.1, scale: 0.2}\n")


def _bomb(levels: int, fan: int = 10) -> str:
    lines = ["l0: &l0 [x]"]
    for i in range(1, levels):
        lines.append(f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * fan) + "]")
    return "\n".join(lines) + "\n"


def test_alias_expansion_is_bounded(monkeypatch):
    # 10 ** 6 leaves at the sixth level: over a million nodes once expanded
    with pytest.raises(ValueError, match=r"aliases expand to more than 1,000,000 values"):
        safe_load_bounded(_bomb(7))
    assert MAX_YAML_NODES == 1_000_000
    # the count is exact: l0 is a list of one leaf (2 nodes); l1 holds it 10 times
    # (1 + 10 * 2 = 21); with the root mapping and its two keys the document is 1 + 1 + 2 + 1 + 21
    text = "l0: &l0 [x]\nl1: [" + ", ".join(["*l0"] * 10) + "]\n"
    monkeypatch.setattr(yamlio, "MAX_YAML_NODES", 26)
    assert safe_load_bounded(text)["l1"] == [["x"]] * 10
    monkeypatch.setattr(yamlio, "MAX_YAML_NODES", 25)
    with pytest.raises(ValueError, match="more than 25 values"):
        safe_load_bounded(text)


def test_an_empty_document_is_none():
    assert safe_load_bounded("") is None
    assert safe_load_bounded("# only a comment\n") is None


def test_load_yaml_errors_are_one_line_naming_the_file(tmp_path):
    missing = tmp_path / "nope.yaml"
    with pytest.raises(FileNotFoundError, match=f"^experiment file not found: {missing}$"):
        load_yaml(missing)
    cases = {
        "syntax.yaml": ("name: x\nterrain: {preset: a\n", "not valid YAML at line 3"),
        "dup.yaml": (
            "name: x\nseed: 1\nseed: 2\n",
            "line 3: duplicate key 'seed' (first at line 2)",
        ),
        "bomb.yaml": (_bomb(7), "its aliases expand to more than 1,000,000 values"),
    }
    for name, (text, message) in cases.items():
        (tmp_path / name).write_text(text)
        with pytest.raises(ConfigError) as info:
            load_yaml(tmp_path / name)
        assert str(info.value).startswith(f"{tmp_path / name}: {message}"), str(info.value)
    (tmp_path / "bin.yaml").write_bytes(b"\xff\xfe\x00name")
    with pytest.raises(ConfigError, match=r"bin\.yaml: not a text file$"):
        load_yaml(tmp_path / "bin.yaml")


def test_load_yaml_reads_an_empty_file_as_an_empty_mapping(tmp_path):
    (tmp_path / "e.yaml").write_text("")
    assert load_yaml(tmp_path / "e.yaml") == {}


def test_parse_set_values_and_errors():
    assert parse_set([" seed = 3", "a.b=x=y", "c=", "d=null"]) == {
        "seed": 3,
        "a.b": "x=y",  # only the first = splits
        "c": None,
        "d": None,
    }
    with pytest.raises(ConfigError, match=r"^--set render\.spp: value is not valid YAML \("):
        parse_set(["render.spp=[1,"])
    with pytest.raises(
        ConfigError,
        match=r"^--set s: value is not valid YAML \(duplicate key 'a' \(first at line 1\)\)$",
    ):
        parse_set(["s={a: 1, a: 2}"])
    with pytest.raises(ConfigError, match=r"^--set nokey: expected key\.path=value$"):
        parse_set(["nokey"])


def test_dump_keeps_key_order_and_round_trips():
    data = {"name": "é", "seed": 1, "study": {"densities": [0.5, 0.125], "b": None}, "a": True}
    text = dump_yaml(data)
    assert text.splitlines()[0] == "name: é" and list(safe_load_text(text)) == [
        "name",
        "seed",
        "study",
        "a",
    ]
    assert safe_load_text(text) == data
    assert safe_load_bounded(text) == data
