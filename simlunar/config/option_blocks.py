"""YAML blocks made of fields of several options classes, with unit-suffixed keys.

A library options class declares each field once with :func:`simlunar.registry.option`
(type, default, doc, SI ``unit``, bounds, choices and, where the YAML writes it in another
unit, ``key_unit``). A YAML block (:class:`Block`) gathers the fields of one or more such
classes (its :class:`Part` s) and derives each key from the declaration: the key's name (the
field's SI suffix replaced by the key unit's: ``fwhm_s`` in ns is ``fwhm_ns``), its type,
default and bounds converted to the key's unit (:data:`KEY_UNITS`), its description (the
doc and the unit). The block turns a validated config back into the library's keywords
(:meth:`Block.library`), the conversion read from the same table, and checks the library's
own rules across fields at load by building the options objects.

A new field of one of those classes is a new YAML key with nothing written here.
"""

from __future__ import annotations

import dataclasses
import math
import re
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Annotated, Any, Literal, Optional

from pydantic import BaseModel, Field, create_model, model_validator

from simlunar.config.fields import Metres, _Model, _SetKeysModel
from simlunar.registry import option_info

__all__ = ["KEY_UNITS", "Block", "Key", "Part", "key_name"]

#: a key unit -> (the SI unit it is a multiple of, the factor: SI value = key value x factor)
KEY_UNITS: dict[str, tuple[str, float]] = {
    "ns": ("s", 1e-9),
    "us": ("s", 1e-6),
    "ms": ("s", 1e-3),
    "uJ": ("J", 1e-6),
    "mJ": ("J", 1e-3),
    "nm": ("m", 1e-9),
    "um": ("m", 1e-6),
    "mm": ("m", 1e-3),
    "urad": ("rad", 1e-6),
    "mrad": ("rad", 1e-3),
    "deg": ("rad", math.pi / 180.0),
}

#: fields written in the YAML in another order than the library's: a (rows, cols) array is
#: (width, height) in the YAML (the guide camera's aspect), converted both ways here
_WIDTH_HEIGHT = ("receiver_px",)


def _suffix(unit: str) -> str:
    """The key suffix of a unit: ``ns`` -> ``_ns``, ``uJ`` -> ``_uj``, ``W/sr`` -> ``_w_sr``."""
    return "_" + re.sub(r"[^a-z0-9]+", "_", unit.lower()).strip("_")


def _factor(info: dict, where: str) -> float:
    """SI value / key value of a field (1 without a key unit)."""
    key_unit, unit = info.get("key_unit"), info.get("unit")
    if key_unit is None or key_unit == unit:
        return 1.0
    if key_unit not in KEY_UNITS or KEY_UNITS[key_unit][0] != unit:
        raise ValueError(f"{where}: key unit {key_unit!r} is no multiple of {unit!r} (KEY_UNITS)")
    return KEY_UNITS[key_unit][1]


def key_name(name: str, info: dict) -> str:
    """The YAML key of a field: its SI suffix replaced by its key unit's (``fwhm_s`` ->
    ``fwhm_ns``), or the key unit's appended to a name without one (``laser_intensity`` ->
    ``laser_intensity_w_sr``); the field's name without a key unit."""
    key_unit, unit = info.get("key_unit"), info.get("unit")
    if key_unit is None:
        return name
    si = _suffix(unit) if unit else None
    base = name.removesuffix(si) if si and name.endswith(si) else name
    return base + _suffix(key_unit)


def _tidy(x: float) -> float:
    """A converted default or bound without the float noise of the division (1e-5 / 1e-9 is
    10000.000000000002; 12 significant digits)."""
    return float(f"{x:.12g}")


@dataclass(frozen=True)
class Key:
    """Where one YAML key's value goes: a field of a part, the factor to SI, what a null means."""

    part: str
    field: str
    factor: float = 1.0
    #: null in the YAML: "skip" = the library's default (an override left unset), "keep" = the
    #: library's None, "hardware" = the instrument's value of the same field, else that value
    null: Any = "keep"
    width_height: bool = False
    nested: Block | None = None

    def to_library(self, value):
        if self.nested is not None and value is not None:
            return self.nested.options(value)
        if value is None:
            return value
        if self.width_height:
            return (value[1], value[0])
        if self.factor != 1.0:
            return value * self.factor
        return value


@dataclass(frozen=True)
class Part:
    """The fields of one options class in a block.

    ``only`` / ``skip`` select fields (default: every field declared with a doc and a
    default, nested options classes left out unless in ``nested``); ``rename`` maps a field to
    another key (before any unit suffix: ``samples`` -> ``footprint_rays``); ``optional``
    fields (or all: True) default to null = the library's default, an override; ``null``
    maps a field to what a null means (``math.inf``; ``"hardware"``: the instrument's value,
    the key's default null); ``nested`` maps a field holding an options object (or None) to
    the block of its own keys; ``limits`` adds bounds (in SI) to a key whose YAML meaning is
    narrower than the field's (an expert override); ``check``: build the options at load, so
    the class's rules across fields name the block (False where a rule reads fields of another
    block).
    """

    name: str
    options: type
    only: tuple[str, ...] | None = None
    skip: tuple[str, ...] = ()
    rename: Mapping[str, str] = field(default_factory=dict)
    optional: bool | tuple[str, ...] = False
    null: Mapping[str, Any] = field(default_factory=dict)
    nested: Mapping[str, Block] = field(default_factory=dict)
    limits: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    check: bool = True

    def infos(self, hints: dict) -> dict[str, dict]:
        info = option_info(self.options)
        names = self.only if self.only is not None else list(info)
        out = {}
        for name in names:
            row = info[name]
            if name in self.skip or row["doc"] is None:
                continue
            if name not in self.nested and (
                row["default"] is dataclasses.MISSING or _holds_options(hints[name])
            ):
                continue  # a nested options object: a block of its own, or the caller's
            out[name] = {**row, **self.limits.get(name, {})}
        return out


def _holds_options(kind) -> bool:
    """Whether an annotation is (or may be) an options dataclass."""
    args = typing.get_args(kind) or (kind,)
    return any(isinstance(a, type) and dataclasses.is_dataclass(a) for a in args)


def _annotation(kind, info: dict, factor: float, width_height: bool):
    """The pydantic type of a key: choices as a Literal, a length in m as :data:`Metres`
    (it takes "20 cm"), a tuple's bounds on each element."""
    if info["choices"] is not None:
        return Literal[tuple(info["choices"])], {}
    bounds = {k: _tidy(info[k] / factor) for k in ("ge", "gt", "le", "lt") if info[k] is not None}
    args = [a for a in typing.get_args(kind) if a is not type(None)]
    base = args[0] if len(args) == 1 and type(None) in typing.get_args(kind) else kind
    if typing.get_origin(base) is tuple:
        elems = typing.get_args(base)
        base = tuple[tuple(Annotated[e, Field(**bounds)] for e in elems)]
        bounds = {}
    elif info["unit"] == "m" and info.get("key_unit") is None and base is float:
        base = Metres
    return base, bounds


def _model_fields(part: Part, hints: dict) -> tuple[dict, dict[str, Key]]:
    fields, keys = {}, {}
    for name, info in part.infos(hints).items():
        where = f"{part.options.__name__}.{name}"
        factor = _factor(info, where)
        key = key_name(part.rename.get(name, name), info)
        null = part.null.get(name, "keep")
        optional = part.optional is True or name in (part.optional or ())
        wh = name in _WIDTH_HEIGHT
        nested = part.nested.get(name)
        desc = info["doc"]
        if nested is not None:
            kind, bounds = Optional[nested.model], {}  # noqa: UP045 - runtime type
        else:
            kind, bounds = _annotation(hints[name], info, factor, wh)
        unit = info.get("key_unit") or info.get("unit")
        if unit and nested is None:
            desc += f" ({unit})"
        if wh:
            desc = desc.replace("(rows, cols)", "(width, height)")
        default = info["default"]
        if optional or null == "hardware":
            default, null = None, ("skip" if optional else null)
            desc += "; null = " + ("the instrument's" if null == "hardware" else "not overridden")
        elif null != "keep":
            desc += f"; null = {null}"
        elif isinstance(default, float) and factor != 1.0:
            default = _tidy(default / factor)
        elif isinstance(default, tuple) and wh:
            default = (default[1], default[0])
        if default is None or null not in ("keep", "skip"):
            kind = Optional[kind]  # noqa: UP045 - runtime type
        fields[key] = (kind, Field(default, description=desc, **bounds))
        keys[key] = Key(part.name, name, factor, null, wh, nested)
    return fields, keys


class Block:
    """A YAML block derived from :class:`Part` s (module docstring); ``model`` is its pydantic
    model, ``keys`` the :class:`Key` of each YAML key.

    ``extra`` fields (a hand-written key of the block alone, e.g. a motion's ``kind``) come
    first and are the caller's to translate; ``set_keys_only`` dumps only the keys set (an
    override block); ``doc`` is the model's docstring.
    """

    def __init__(self, name: str, doc: str, parts: tuple[Part, ...], *, extra=None,
                 set_keys_only: bool = False, validators: tuple[Callable, ...] = ()):  # fmt: skip
        self.name, self.parts = name, {p.name: p for p in parts}
        fields = dict(extra or {})
        self.keys: dict[str, Key] = {}
        for part in parts:
            f, k = _model_fields(part, typing.get_type_hints(part.options))
            clash = set(f) & set(fields)
            if clash:
                raise ValueError(f"{name}: key {sorted(clash)[0]!r} comes from two fields")
            fields.update(f)
            self.keys.update(k)
        block = self

        class _Base(_SetKeysModel if set_keys_only else _Model):
            @model_validator(mode="after")
            def _library_rules(self):
                block.check(self)
                for rule in validators:
                    rule(self)
                return self

        self.model: type[BaseModel] = create_model(name, __base__=_Base, __doc__=doc, **fields)

    def library(self, cfg, part: str, *, hardware=None) -> dict[str, Any]:
        """The keywords of part ``part``'s options class from a validated config ``cfg``
        (SI units; keys left null as an override left out; ``hardware``: the instrument, whose
        fields fill the keys that take them)."""
        out = {}
        for key, k in self.keys.items():
            if k.part != part:
                continue
            value = getattr(cfg, key)
            if value is None and k.null == "skip":
                continue
            if value is None and k.null == "hardware":
                value = None if hardware is None else getattr(hardware, k.field, None)
                if value is None:
                    continue
                out[k.field] = value
                continue
            if value is None and k.null != "keep":
                out[k.field] = k.null
                continue
            out[k.field] = k.to_library(value)
        return out

    def options(self, cfg, part: str | None = None, **more):
        """The options object of part ``part`` (default: the only one) from ``cfg``, with
        ``more`` keywords (nested options the block does not hold)."""
        name = part or next(iter(self.parts))
        return self.parts[name].options(**self.library(cfg, name), **more)

    def check(self, cfg) -> None:
        """Build every checked part's options: a rule of the library across fields fails at
        load, naming the block."""
        for name, part in self.parts.items():
            if not part.check:
                continue
            part.options(**self.library(cfg, name))

    def key_of(self, options_cls: type, field_name: str) -> str | None:
        """The YAML key of ``options_cls.field_name`` in this block (None: not in it)."""
        for key, k in self.keys.items():
            if self.parts[k.part].options is options_cls and k.field == field_name:
                return key
        return None

    def default(self):
        """The block's defaults (a model with every key at its default)."""
        return self.model()
