"""Reading YAML: duplicate keys refused, one-line errors naming the file and line; ``--set`` values."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from simlunar.errors import ConfigError

#: what the YAML reader raises on invalid text
YAMLError = yaml.YAMLError

__all__ = [
    "UniqueKeyLoader",
    "YAMLError",
    "dump_yaml",
    "load_yaml",
    "parse_set",
    "safe_load_text",
]


def parse_set(items: list[str]) -> dict[str, Any]:
    """``--set key.path=value`` overrides; values parsed as YAML (``5``, ``[1, 2]``, ``lambert``)."""
    out = {}
    for item in items:
        if "=" not in item:
            raise ConfigError(f"--set {item}: expected key.path=value")
        key, raw = item.split("=", 1)
        try:
            out[key.strip()] = yaml.safe_load(raw)
        except yaml.YAMLError as exc:
            raise ConfigError(f"--set {key}: value is not valid YAML ({exc.problem})") from None
    return out


class UniqueKeyLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses a key given twice in one mapping (PyYAML keeps the
    last value silently)."""

    def construct_mapping(self, node, deep=False):
        seen = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            try:
                hash(key)
            except TypeError:
                continue  # the base class reports unhashable keys
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None,
                    None,
                    f"duplicate key {key!r} (first at line {seen[key] + 1})",
                    key_node.start_mark,
                )
            seen[key] = key_node.start_mark.line
        return super().construct_mapping(node, deep=deep)


def load_yaml(path: str | Path) -> dict:
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"experiment file not found: {path}")
    try:
        data = yaml.load(path.read_text(), Loader=UniqueKeyLoader)
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not a text file") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or ""
        if problem.startswith("duplicate key"):
            raise ConfigError(f"{path}: line {mark.line + 1}: {problem}") from None
        raise ConfigError(f"{path}: not valid YAML{where}") from None
    return data if data is not None else {}


def dump_yaml(data: Any) -> str:
    """YAML text of plain data, keys in their given order (a result folder's ``config.yaml``)."""
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


def safe_load_text(text: str) -> Any:
    """Plain data of YAML text written by :func:`dump_yaml` (``yaml.YAMLError`` if invalid)."""
    return yaml.safe_load(text)
