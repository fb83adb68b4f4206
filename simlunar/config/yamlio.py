"""Reading YAML: duplicate keys refused, merge keys accepted, alias expansion bounded, one-line
errors naming the file and line; ``--set`` values."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from simlunar.errors import ConfigError

#: what the YAML reader raises on invalid text
YAMLError = yaml.YAMLError

__all__ = [
    "MAX_YAML_NODES",
    "UniqueKeyLoader",
    "YAMLError",
    "dump_yaml",
    "load_yaml",
    "parse_set",
    "safe_load_bounded",
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
            out[key.strip()] = safe_load_bounded(raw)
        except yaml.YAMLError as exc:
            raise ConfigError(f"--set {key}: value is not valid YAML ({exc.problem})") from None
        except ValueError as exc:
            raise ConfigError(f"--set {key}: {exc}") from None
    return out


class UniqueKeyLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses a key given twice in one mapping (PyYAML keeps the
    last value silently). Merge keys (``<<: *anchor``) work: a key given explicitly
    overrides the merged one, as YAML specifies; only explicit keys must be unique."""

    def construct_mapping(self, node, deep=False):
        seen = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue  # flattened by the base class; its keys may be overridden
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


#: most nodes a document may hold once its aliases are expanded: an alias names its anchor's
#: value without copying it, so a few lines of nested aliases ("billion laughs") stand for a
#: tree that every later step (validation, sweeps, config.yaml) would walk in full
MAX_YAML_NODES = 1_000_000


def _expanded_size(root) -> int:
    """Nodes of the tree under ``root`` with every alias expanded (ValueError beyond
    :data:`MAX_YAML_NODES` or for a recursive alias)."""
    memo: dict[int, int] = {}
    active: set[int] = set()

    def size(node) -> int:
        key = id(node)
        if key in memo:
            return memo[key]
        if key in active:
            raise ValueError("a recursive alias (an anchor used inside its own value)")
        active.add(key)
        n = 1
        if isinstance(node, yaml.SequenceNode):
            n += sum(size(c) for c in node.value)
        elif isinstance(node, yaml.MappingNode):
            n += sum(size(k) + size(v) for k, v in node.value)
        active.discard(key)
        if n > MAX_YAML_NODES:
            raise ValueError(
                f"its aliases expand to more than {MAX_YAML_NODES:,} values (an alias bomb?)"
            )
        memo[key] = n
        return n

    return size(root)


#: most characters of a YAML document (an experiment is a few kB; a preset or training file too)
MAX_YAML_CHARS = 10_000_000
#: deepest nesting of collections in a YAML document: PyYAML composes nested collections
#: recursively, so 5000 nested brackets would exhaust Python's stack (an experiment nests < 10)
MAX_YAML_DEPTH = 100

_OPENS = (
    yaml.BlockMappingStartToken,
    yaml.BlockSequenceStartToken,
    yaml.FlowMappingStartToken,
    yaml.FlowSequenceStartToken,
)
_CLOSES = (yaml.BlockEndToken, yaml.FlowMappingEndToken, yaml.FlowSequenceEndToken)


def _check_bounds(text: str) -> None:
    """Refuse (``ValueError``) a document above :data:`MAX_YAML_CHARS` or nested deeper than
    :data:`MAX_YAML_DEPTH`, from the token stream (the scanner is iterative), before the
    recursive composer sees it."""
    if len(text) > MAX_YAML_CHARS:
        raise ValueError(
            f"the document has {len(text):.3g} characters, more than {MAX_YAML_CHARS:.0e}"
        )
    depth = 0
    for tok in yaml.scan(text, Loader=yaml.SafeLoader):
        if isinstance(tok, _OPENS):
            depth += 1
            if depth > MAX_YAML_DEPTH:
                line = tok.start_mark.line + 1
                raise ValueError(f"line {line}: collections nested more than {MAX_YAML_DEPTH} deep")
        elif isinstance(tok, _CLOSES):
            depth -= 1


def safe_load_bounded(text: str):
    """``yaml.load`` with :class:`UniqueKeyLoader`, refusing documents larger than
    :data:`MAX_YAML_CHARS`, nested deeper than :data:`MAX_YAML_DEPTH` or whose aliases expand
    beyond :data:`MAX_YAML_NODES` (``ValueError``); YAML errors as ``yaml.YAMLError``."""
    _check_bounds(text)
    loader = UniqueKeyLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _expanded_size(node)
        return loader.construct_document(node)
    finally:
        loader.dispose()


def load_yaml(path: str | Path) -> dict:
    path = Path(path)
    if not path.is_file():
        # imported here: `simlunar run --help` imports this module and nothing of simlunar else
        from simlunar.registry import did_you_mean_file

        raise FileNotFoundError(f"experiment file not found: {path}{did_you_mean_file(path)}")
    try:
        data = safe_load_bounded(path.read_text())
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not a text file") from None
    except ValueError as exc:
        raise ConfigError(f"{path}: {exc}") from None
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
