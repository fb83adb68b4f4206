"""Field types and base models of the configuration schema.

Every model forbids unknown keys and non-finite numbers; unit-bearing keys (``_deg``, ``_m``) accept a
number in that unit or a string with an explicit unit, converted once here.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from typing import Annotated, Literal, Optional, Union

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    StringConstraints,
    Tag,
    create_model,
    model_serializer,
    model_validator,
)

from simlunar.config.quantities import parse_fraction, parse_quantity
from simlunar.registry import option_info

__all__ = ["Deg", "Density", "Metres", "Px", "PxCount", "unique_names"]

#: what a unit-bearing key accepts in the YAML (for the editor schema): a number in the key's
#: unit or a string with an explicit unit ("0.5 rad", "20 cm")
_QUANTITY_INPUT = float | Annotated[str, StringConstraints(pattern=r"^\s*[-+]?[0-9.]")]
_FRACTION_INPUT = (
    float | Annotated[str, StringConstraints(pattern=r"^\s*[0-9.]+(\s*/\s*[0-9.]+)?\s*$")]
)

Deg = Annotated[
    float,
    BeforeValidator(lambda v: parse_quantity(v, "deg"), json_schema_input_type=_QUANTITY_INPUT),
]
Metres = Annotated[
    float,
    BeforeValidator(lambda v: parse_quantity(v, "m"), json_schema_input_type=_QUANTITY_INPUT),
]
Density = Annotated[float, BeforeValidator(parse_fraction, json_schema_input_type=_FRACTION_INPUT)]
Px = Annotated[
    float,
    BeforeValidator(lambda v: parse_quantity(v, "px"), json_schema_input_type=_QUANTITY_INPUT),
    Field(ge=0),
]


def _whole_px(v):
    """A pixel count: an integer, or a string such as ``"256 px"`` naming one."""
    if isinstance(v, str):
        f = parse_quantity(v, "px")
        if f != int(f):
            raise ValueError(f"expected a whole number of pixels, got {v!r}")
        return int(f)
    return v


PxCount = Annotated[
    int,
    BeforeValidator(_whole_px, json_schema_input_type=int | str),
    Field(gt=0),
]


class _Model(BaseModel):
    # finite numbers only: .inf / .nan in a YAML is a one-line error with its key path
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


def unique_names(v: list[str]) -> list[str]:
    """A list of names without repeats (the field validator of a study's name lists)."""
    if len(set(v)) != len(v):
        raise ValueError(f"names must be unique, got {v}")
    return v


class _SetKeysModel(_Model):
    """Serialises the keys that are set (not None) only: an override names what it changes."""

    @model_serializer(mode="wrap")
    def _set_keys_only(self, handler):
        return {k: v for k, v in handler(self).items() if v is not None}


def _partial(model: type[BaseModel]) -> type[BaseModel]:
    """``model`` with every field optional (default None = keep the value it overrides)."""
    fields = {}
    for name, f in model.model_fields.items():
        info = f._copy()
        info.default = None
        info.default_factory = None
        fields[name] = (Optional[f.annotation], info)  # noqa: UP045 - runtime type
    return create_model(
        f"{model.__name__}Override",
        __base__=_SetKeysModel,
        __doc__=f"Overrides of {model.__name__} (unset keys keep the preset's value).",
        **fields,
    )


def _tagged_union(default: str | None, *members: type[BaseModel]):
    """A union chosen by its ``kind`` key; a missing ``kind`` means ``default``."""
    tags = [m.model_fields["kind"].annotation.__args__[0] for m in members]

    def pick(v):
        if isinstance(v, dict):
            return v.get("kind", default)
        return getattr(v, "kind", default)

    union = Union[tuple(Annotated[m, Tag(t)] for m, t in zip(members, tags))]  # noqa: UP007
    return Annotated[
        union,
        Discriminator(
            pick,
            custom_error_type="bad_kind",
            custom_error_message=f"kind must be one of {', '.join(tags)}",
        ),
    ]


def options_model(
    options_cls, name: str, doc: str = "", *, base=None, extra=None
) -> type[BaseModel]:
    """A pydantic model of an options dataclass's fields declared with
    :func:`simlunar.registry.option` (type, default, doc, bounds, choices as a ``Literal``).

    Fields declared without ``option`` (set by the library, e.g. ``keep_frames``) are left
    out. An angle (``unit="rad"``) becomes the key ``<name>_deg`` in degrees (default and
    bounds converted; :func:`library_values` converts back). ``extra`` fields (e.g. a
    ``kind`` tag) come first. ``model_dump()`` of the model, through :func:`library_values`,
    is the keyword set of ``options_cls``; the options class is built from it at validation,
    so its own rules across fields (``__post_init__``) refuse a YAML block at load, not after
    the run has started.
    """
    hints = typing.get_type_hints(options_cls)
    fields = dict(extra or {})
    for key, info in option_info(options_cls).items():
        if info["doc"] is None or info["default"] is dataclasses.MISSING:
            continue
        kind, default = hints[key], info["default"]
        bounds = {k: info[k] for k in ("ge", "gt", "le", "lt") if info[k] is not None}
        unit = info["unit"]
        if info["choices"] is not None:
            kind = Literal[tuple(info["choices"])]
        if info.get("file") is not None:  # the marker the cache key's file walk reads
            kind = Annotated[kind, info["file"]]
        if unit == "rad":
            key, kind, unit = f"{key}_deg", Deg, "deg"
            default = math.degrees(default)
            bounds = {k: math.degrees(v) for k, v in bounds.items()}
        desc = info["doc"] + (f" ({unit})" if unit else "")
        fields[key] = (kind, Field(default, description=desc, **bounds))
    base = base or _Model

    def _class_rules(self):
        try:
            options_cls(**library_values(self))
        except TypeError:  # a class the library completes (a required field set at run time)
            pass
        return self

    return create_model(
        name,
        __base__=base,
        __doc__=doc or options_cls.__doc__,
        __validators__={"_class_rules": model_validator(mode="after")(_class_rules)},
        **fields,
    )


def library_values(model: BaseModel, *, drop=("kind",)) -> dict:
    """The library keywords of a config model: keys ``<name>_deg`` converted to radians under
    ``<name>``, None values (library default) and the ``drop`` keys left out."""
    out = {}
    for key, value in model.model_dump().items():
        if key in drop or value is None:
            continue
        if key.endswith("_deg"):
            key, value = key.removesuffix("_deg"), math.radians(value)
        out[key] = value
    return out
