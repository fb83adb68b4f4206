"""Field types and base models of the configuration schema.

Every model forbids unknown keys and non-finite numbers; unit-bearing keys (``_deg``, ``_m``) accept a
number in that unit or a string with an explicit unit, converted once here.
"""

from __future__ import annotations

from typing import Annotated, Optional, Union

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
)

from simlunar.config.quantities import parse_fraction, parse_quantity

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
