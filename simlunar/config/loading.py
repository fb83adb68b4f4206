"""Loading and validating experiment YAMLs: one-line errors with key paths, sweeps, overrides.

The models are in :mod:`simlunar.config.schema` (re-exported here). Every problem is
reported as a :class:`simlunar.errors.ConfigError` whose one-line message names the key path
(``render.light.elevation_deg: ...``); see :func:`load_experiment`.
"""

from __future__ import annotations

import copy
import re
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ValidationError

from simlunar.config.fields import _Model
from simlunar.config.schema import ExperimentCfg
from simlunar.config.studies import SamplingStudyCfg, ScannerStudyCfg
from simlunar.errors import ConfigError


# --------------------------------------------------------------------------- loading
def _loc_path(loc: tuple, data: Any) -> str:
    """Key path of a pydantic error location, dropping union tags that are not real keys."""
    parts: list[str] = []
    cur = data
    for item in loc:
        if isinstance(cur, dict) and item in cur:
            parts.append(str(item))
            cur = cur[item]
        elif isinstance(cur, list) and isinstance(item, int):
            parts.append(f"[{item}]")
            cur = cur[item] if item < len(cur) else None
        elif isinstance(item, int):
            parts.append(f"[{item}]")
            cur = None
        elif _is_field_name(str(item)):
            parts.append(str(item))
            cur = None
    return ".".join(parts).replace(".[", "[") or "<root>"


def _union_tags() -> frozenset[str]:
    """The ``kind`` values of every model (pydantic puts them in error locations of unions)."""
    tags: set[str] = set()
    todo = list(_Model.__subclasses__())
    while todo:
        m = todo.pop()
        todo.extend(m.__subclasses__())
        f = m.model_fields.get("kind")
        if f is not None:
            tags.update(a for a in getattr(f.annotation, "__args__", ()) if isinstance(a, str))
    return frozenset(tags)


def _is_field_name(item: str) -> bool:
    return item not in _union_tags() and "[" not in item


def _message(err: dict) -> str:
    msg = err["msg"]
    if err["type"] == "extra_forbidden":
        return "unknown key"
    if msg.startswith("Value error, "):
        msg = msg[len("Value error, ") :]
    if msg.startswith("Assertion failed, "):
        msg = msg[len("Assertion failed, ") :]
    return msg


def _unknown_key_hint(path: str, data: dict) -> str:
    """Suggest the valid keys where an unknown key was found."""
    parent = path.rsplit(".", 1)[0] if "." in path else ""
    try:
        keys = valid_keys(parent, data)
    except ConfigError:
        return ""
    return f" (valid keys: {', '.join(keys)})" if keys else ""


def _nested_key(loc: tuple, data: Any, msg: str) -> tuple[str, str] | None:
    """``(sub.path, problem)`` when a validator reported a key inside its own mapping value.

    A model validator says ``"options.rig.elevation_deg: ..."``; when that key path exists in
    the data under the error's location, it belongs to the path (union tags in the location,
    which are not keys of the data, are skipped).
    """
    m = re.match(r"^([A-Za-z_]\w*(?:\.\w+)*): (.+)$", msg)
    if m is None:
        return None
    cur: Any = data
    items = (*loc, *m.group(1).split("."))
    for i, item in enumerate(items):
        if isinstance(cur, dict) and item in cur:
            cur = cur[item]
        elif isinstance(cur, list) and isinstance(item, int) and item < len(cur):
            cur = cur[item]
        elif isinstance(item, str) and item in _union_tags():
            continue
        elif i == len(items) - 1 and isinstance(cur, dict):
            break  # a key the data lacks (a missing value the validator asks for)
        else:
            return None
    return m.group(1), m.group(2)


def format_validation_error(exc: ValidationError, data: Any, prefix: str = "") -> str:
    """One line for the first error of ``exc``: ``<key.path>: <problem>``."""
    err = exc.errors()[0]
    path = _loc_path(tuple(err["loc"]), data)
    msg = _message(err)
    nested = _nested_key(tuple(err["loc"]), data, msg) if err["type"] == "value_error" else None
    if nested is not None:
        path = nested[0] if path == "<root>" else f"{path}.{nested[0]}"
        msg = nested[1]
    if prefix:
        path = f"{prefix}.{path}" if path != "<root>" else prefix
    if err["type"] == "extra_forbidden" and isinstance(data, dict):
        msg += _unknown_key_hint(_loc_path(tuple(err["loc"]), data), data)
    return f"{path}: {msg}"


def _model_at(path: str, data: dict) -> type[BaseModel] | None:
    """The model class that holds the keys under ``path`` (``""`` = root) for this data."""
    model: type[BaseModel] = ExperimentCfg
    cur: Any = data
    if not path:
        return model
    for part in path.split("."):
        if part not in model.model_fields:
            raise ConfigError(f"{path}: no such key {part!r}")
        ann = model.model_fields[part].annotation
        cur = cur.get(part) if isinstance(cur, dict) else None
        model = _resolve_model(ann, cur, part)
        if model is None:
            return None
    return model


def _resolve_model(ann: Any, value: Any, name: str) -> type[BaseModel] | None:
    """The concrete model of a field annotation, choosing union members by ``kind``."""
    args = getattr(ann, "__args__", None)
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        return ann
    if args:
        members = [a for a in _flatten(ann) if isinstance(a, type) and issubclass(a, BaseModel)]
        if not members:
            return None
        kind = value.get("kind") if isinstance(value, dict) else None
        if kind is not None:
            for m in members:
                if m.model_fields.get("kind") and kind in _literal_values(m.model_fields["kind"]):
                    return m
        # no kind given: the member with a default kind
        for m in members:
            f = m.model_fields.get("kind")
            if f is None or (f.default is not None and not f.is_required()):
                return m
        return members[0]
    return None


def _flatten(ann: Any) -> list:
    out = []
    for a in getattr(ann, "__args__", ()) or ():
        if getattr(a, "__args__", None) and not (isinstance(a, type) and issubclass(a, BaseModel)):
            out.extend(_flatten(a))
        else:
            out.append(a)
    meta = getattr(ann, "__metadata__", None)
    if meta is not None and hasattr(ann, "__origin__"):
        out.extend(_flatten(ann.__origin__))
    return out


def _literal_values(field) -> tuple:
    return getattr(field.annotation, "__args__", ())


def valid_keys(path: str, data: dict) -> list[str]:
    """Keys allowed under the dotted ``path`` for this data (``kind`` picks union members)."""
    model = _model_at(path, data)
    if model is None:
        return []
    return [f.alias or name for name, f in model.model_fields.items()]


def get_path(data: dict, path: str) -> Any:
    cur: Any = data
    for part in path.split("."):
        if not isinstance(cur, dict) or part not in cur:
            return None
        cur = cur[part]
    return cur


def set_path(data: dict, path: str, value: Any) -> dict:
    """A deep copy of ``data`` with the dotted ``path`` set to ``value`` (parents created)."""
    out = copy.deepcopy(data)
    cur = out
    parts = path.split(".")
    for part in parts[:-1]:
        nxt = cur.get(part)
        if not isinstance(nxt, dict):
            nxt = {}
            cur[part] = nxt
        cur = nxt
    cur[parts[-1]] = value
    return out


def apply_sweep_value(data: dict, path: str, value: Any) -> dict:
    """``data`` with one sweep (or ``--set``) value applied.

    Setting a ``kind`` resets its section to that kind's defaults, because the other keys of
    the old kind (``elevation_deg`` of a sun) are not valid for the new one (a camera light).
    """
    parts = path.split(".")
    if parts[-1] == "kind" and len(parts) > 1:
        return set_path(data, ".".join(parts[:-1]), {"kind": value})
    return set_path(data, path, value)


def check_key_path(path: str, data: dict) -> None:
    """Raise ConfigError unless ``path`` names a settable key of the schema for this data
    (``terrain.overrides.fractal.rms_m`` included: the overrides are typed preset sections).

    Keys inside mappings with free labels (``study.strategy_options.<label>``) are not
    settable one by one; set the whole mapping.
    """
    parts = path.split(".")
    parent = ".".join(parts[:-1])
    try:
        keys = valid_keys(parent, data)
        model = _model_at(parent, data)
    except ConfigError:
        keys, model = [], None
    if model is None or parts[-1] not in keys:
        # name the keys of the deepest section of the path that exists
        hint = ""
        for n in range(len(parts) - 1, -1, -1):
            prefix = ".".join(parts[:n])
            try:
                keys = valid_keys(prefix, data) if _model_at(prefix, data) is not None else []
            except ConfigError:
                continue
            if keys:
                hint = f" (valid keys under {prefix or 'the root'}: {', '.join(keys)})"
                break
        raise ConfigError(f"sweep.{path}: no such key in the experiment schema{hint}")
    if parts[0] in ("sweep", "name"):
        raise ConfigError(f"sweep.{path}: this key cannot be swept")


def validate_data(data: Any, *, base_dir: Path | None = None) -> ExperimentCfg:
    """Validate a parsed YAML mapping, including every sweep point and referenced files.

    Raises
    ------
    ConfigError
        One line naming the key path and the problem.
    """
    if not isinstance(data, dict):
        raise ConfigError(f"<root>: expected a mapping of keys, got {type(data).__name__}")
    try:
        cfg = ExperimentCfg.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(format_validation_error(exc, data)) from None
    normalised: dict[str, list] = {}
    for path, values in cfg.sweep.items():
        check_key_path(path, data)
        if not values:
            raise ConfigError(f"sweep.{path}: give at least one value")
        normalised[path] = []
        for i, v in enumerate(values):
            point = apply_sweep_value({k: x for k, x in data.items() if k != "sweep"}, path, v)
            try:
                model = ExperimentCfg.model_validate(point)
            except ValidationError as exc:
                raise ConfigError(
                    f"sweep.{path}[{i}]: " + format_validation_error(exc, point)
                ) from None
            normalised[path].append(_normalised_value(v, model, path))
    if normalised != cfg.sweep:
        cfg = cfg.model_copy(update={"sweep": normalised})
    cfg = resolve_terrain_files(cfg, base_dir)
    _check_registries(cfg, data)
    return cfg


def _has_text(v: Any) -> bool:
    if isinstance(v, str):
        return True
    return isinstance(v, list) and any(isinstance(x, str) for x in v)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _normalised_value(raw: Any, point: ExperimentCfg, path: str) -> Any:
    """A sweep value as the model holds it when the YAML gave text for a number
    (``"0.5 rad"`` -> 28.64..., ``"1/32"`` -> 0.03125); other values as written, so
    results.csv keeps ``30`` (not ``30.0``) in the column of a plain number."""
    if not _has_text(raw):
        return raw
    value = get_path(point.model_dump(mode="json", by_alias=True), path)
    if _is_number(value) or (isinstance(value, list) and value and all(map(_is_number, value))):
        return value
    return raw


def _check_registries(cfg: ExperimentCfg, data: dict) -> None:
    """Names that select code (preset, strategy, metric) must exist."""
    from simlunar.config import registry

    points = [cfg]
    for path, values in cfg.sweep.items():
        for v in values:
            points.append(
                ExperimentCfg.model_validate(
                    apply_sweep_value({k: x for k, x in data.items() if k != "sweep"}, path, v)
                )
            )
    for p in points:
        if p.terrain.preset is not None:
            registry.check_preset(p.terrain.preset, "terrain.preset")
        if isinstance(p.study, SamplingStudyCfg):
            for i, s in enumerate(p.study.strategies):
                registry.check_strategy(s, f"study.strategies[{i}]", p.study.strategy_options)
            for i, m in enumerate(p.study.metrics):
                registry.check_metric(m, f"study.metrics[{i}]")
        if isinstance(p.study, ScannerStudyCfg):
            for i, s in enumerate(p.study.planners):
                registry.check_scan_planner(s, f"study.planners[{i}]")
            for i, m in enumerate(p.study.modes):
                registry.check_scan_mode(m, f"study.modes[{i}]")


def resolve_terrain_files(cfg, base_dir: Path | None):
    """Resolve ``terrain.file`` / ``terrain.albedo_file`` relative to ``base_dir`` (the YAML's
    folder) and check they exist; works on any config model with a ``terrain`` section."""
    t = cfg.terrain
    updates = {}
    for key in ("file", "albedo_file"):
        p = getattr(t, key)
        if p is None:
            continue
        full = (base_dir / p) if (base_dir is not None and not p.is_absolute()) else p
        if not full.is_file():
            raise ConfigError(f"terrain.{key}: file not found: {full}")
        updates[key] = full.resolve()
    if updates:
        cfg = cfg.model_copy(update={"terrain": t.model_copy(update=updates)})
    return cfg


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


def load_experiment(path: str | Path, overrides: dict[str, Any] | None = None) -> ExperimentCfg:
    """Read, override (dotted keys) and validate an experiment YAML.

    Raises
    ------
    FileNotFoundError
        The YAML (or a file it names) does not exist.
    ConfigError
        ``<file>: <key.path>: <problem>`` on one line.
    """
    path = Path(path)
    data = load_yaml(path)
    for key, value in (overrides or {}).items():
        if not isinstance(data, dict):
            break
        if key.split(".")[0] != "sweep":
            try:
                check_key_path(key, data)
            except ConfigError as exc:
                raise ConfigError(f"{path}: --set " + str(exc).removeprefix("sweep.")) from None
        data = apply_sweep_value(data, key, value)
    try:
        return validate_data(data, base_dir=path.parent)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None


def to_plain(cfg: ExperimentCfg) -> dict:
    """JSON/YAML-safe dict of a config (paths as strings, aliases used)."""
    return cfg.model_dump(mode="json", by_alias=True)


#: document kinds of :func:`json_schema`: experiment YAMLs, scene YAMLs, terrain presets
SCHEMA_KINDS = ("experiment", "scene", "preset")


def schema_model(kind: str = "experiment") -> type[BaseModel]:
    """The root model of a document kind (:data:`SCHEMA_KINDS`)."""
    if kind == "experiment":
        return ExperimentCfg
    if kind == "scene":
        from simlunar.config.scene import SceneCfg

        return SceneCfg
    if kind == "preset":
        from simlunar.config.terrain import TerrainPresetCfg

        return TerrainPresetCfg
    raise ValueError(f"unknown schema kind {kind!r} (valid: {', '.join(SCHEMA_KINDS)})")


def json_schema(kind: str = "experiment") -> dict:
    """JSON Schema of an experiment, scene or terrain-preset YAML (for editors:
    yaml-language-server). Unit-bearing keys accept a number or a string with a unit;
    densities accept a number, a fraction string or (a list) a ``{from, to, count}`` range."""
    schema = schema_model(kind).model_json_schema(by_alias=True)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = f"simlunar {kind}"
    return schema
