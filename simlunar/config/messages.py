"""One-line messages for validation errors: ``<key.path>: <problem>`` with the valid keys.

Generic over the root model (an experiment, a scene or a terrain preset), so every YAML the
project reads reports its errors the same way.
"""

from __future__ import annotations

import re
import typing
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from simlunar.config.fields import _Model
from simlunar.errors import ConfigError
from simlunar.registry import did_you_mean

#: a pydantic model class
M = TypeVar("M", bound=BaseModel)

__all__ = [
    "format_validation_error",
    "is_label_mapping",
    "model_at",
    "valid_keys",
    "validate_file_data",
]


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


def _at_parent(lookup, path: str, data: dict, root: type[BaseModel]) -> tuple[Any, str]:
    """``(lookup(parent, data, root), last)`` of a dotted ``path``; the lookup is None where
    the parent is not in the config (a ``ConfigError``)."""
    parent, _, last = path.rpartition(".")
    try:
        return lookup(parent, data, root), last
    except ConfigError:
        return None, last


def _unknown_key_hint(path: str, data: dict, root: type[BaseModel]) -> str:
    """Suggest the valid keys where an unknown key was found."""
    keys, key = _at_parent(valid_keys, path, data, root)
    return f" (valid keys: {', '.join(keys)}){did_you_mean(key, keys)}" if keys else ""


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


def format_validation_error(
    exc: ValidationError, data: Any, prefix: str = "", *, root: type[BaseModel] | None = None
) -> str:
    """One line for the first error of ``exc``: ``<key.path>: <problem>``; an unknown key lists
    the valid keys of its section when ``root`` (the model ``data`` was validated against) is given."""
    errors = exc.errors()
    # an unknown key first: a misspelt key (``studdy:``) also leaves its real key missing,
    # and "study: Field required" alone would not name what the user wrote
    err = next((e for e in errors if e["type"] == "extra_forbidden"), errors[0])
    path = _loc_path(tuple(err["loc"]), data)
    msg = _message(err)
    nested = _nested_key(tuple(err["loc"]), data, msg) if err["type"] == "value_error" else None
    if nested is not None:
        path = nested[0] if path == "<root>" else f"{path}.{nested[0]}"
        msg = nested[1]
    if prefix:
        path = f"{prefix}.{path}" if path != "<root>" else prefix
    if err["type"] == "extra_forbidden" and isinstance(data, dict) and root is not None:
        msg += _unknown_key_hint(_loc_path(tuple(err["loc"]), data), data, root)
    return f"{path}: {msg}"


def model_at(path: str, data: dict, root: type[BaseModel]) -> type[BaseModel] | None:
    """The model class that holds the keys under ``path`` (``""`` = ``root``) for this data."""
    model: type[BaseModel] | None = root
    cur: Any = data
    parts = path.split(".") if path else []
    i = 0
    while i < len(parts) and model is not None:
        part = parts[i]
        if part not in model.model_fields:
            raise ConfigError(f"{path}: no such key {part!r}")
        field = model.model_fields[part]
        ann = field.annotation
        cur = cur.get(part) if isinstance(cur, dict) else None
        value_ann = _mapping_value(ann)
        if value_ann is None:
            model = _resolve_model(ann, cur, part)
            if model is None and isinstance(cur, dict):
                # a mapping the YAML wrote where the field turns it into something else
                # (study.densities: {from, to, count} -> a list): its input model holds the keys
                model = _input_model(field, cur, part)
            i += 1
        elif i + 1 == len(parts):
            return None  # a mapping with free labels (study.strategy_options) has no fixed keys
        else:  # the next part is a label of the mapping; its value is the model
            label = parts[i + 1]
            cur = cur.get(label) if isinstance(cur, dict) else None
            model = _resolve_model(value_ann, cur, label)
            i += 2
    return model


def _input_model(field, value: Any, name: str) -> type[BaseModel] | None:
    """The model among a field's declared input types (``BeforeValidator(...,
    json_schema_input_type=list[X] | Model)``), chosen for ``value``."""
    for meta in getattr(field, "metadata", ()) or ():
        input_type = getattr(meta, "json_schema_input_type", None)
        if input_type is not None:
            model = _resolve_model(input_type, value, name)
            if model is not None:
                return model
    return None


def _mapping_value(ann: Any) -> Any:
    """The value annotation of a ``dict[str, X]`` field (``X | None`` unwrapped), else None."""
    for a in (ann, *getattr(ann, "__args__", ())):
        if typing.get_origin(a) is dict:
            return typing.get_args(a)[1]
    return None


def is_label_mapping(path: str, data: dict, root: type[BaseModel]) -> bool:
    """Whether ``path`` names a mapping whose keys are free labels (``study.strategy_options``)."""
    model, last = _at_parent(model_at, path, data, root)
    field = model.model_fields.get(last) if model is not None else None
    return field is not None and _mapping_value(field.annotation) is not None


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


def valid_keys(path: str, data: dict, root: type[BaseModel]) -> list[str]:
    """Keys allowed under the dotted ``path`` of a ``root`` document for this data (``kind``
    picks union members)."""
    model = model_at(path, data, root)
    if model is None:
        return []
    return [f.alias or name for name, f in model.model_fields.items()]


def validate_file_data(model: type[M], data: Any, path) -> M:
    """``model`` validated from ``data``, the YAML mapping read from file ``path``; otherwise a
    one-line :class:`~simlunar.errors.ConfigError` ``<path>: <key.path>: <problem>``."""
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(f"{path}: {format_validation_error(exc, data, root=model)}") from None
