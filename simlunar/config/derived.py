"""YAML schemas derived from a component's options dataclass (:mod:`simlunar.registry`).

A component registered as ``name -> (callable, OptionsClass)`` declares each option once, with
:func:`simlunar.registry.option` (type, default, bounds, choices, doc). :func:`options_model`
turns that declaration into a pydantic model, so the YAML section of the component validates
exactly what the library accepts -- the types, the bounds ``ge``/``gt``/``le``/``lt`` and the
choices -- before anything runs, and the editor schema documents each key with its ``doc``.
Nothing is copied by hand: a new option of the dataclass is a new YAML key.
"""

from __future__ import annotations

import dataclasses
import functools
import typing
from collections.abc import Mapping
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, create_model, model_validator

from simlunar.reconstruction import RECONSTRUCTIONS
from simlunar.registry import did_you_mean, option_info
from simlunar.study.reconstruction_spec import ReconstructionSpec, parse_reconstructions

__all__ = [
    "ComponentList",
    "options_model",
    "reconstruction_mapping",
    "reconstruction_specs",
    "validate_options",
]


@dataclasses.dataclass(frozen=True)
class ComponentList:
    """Marks a YAML field whose value stays plain after validation: a list of a registry's
    names or ``{label: {options}}`` mappings (``study.reconstructions``), so that a walk over
    the declarations (the cache key's files) finds each item's options class."""

    registry: Any
    #: the options key naming the registered component of an item under a label of its own
    base_key: str

    def items(self, value) -> list[tuple[str, type, dict]]:
        """(label, options class, options) of each item of a plain value; items naming no
        registered component are left out (the validation reports them)."""
        out = []
        for item in value if isinstance(value, (list, tuple)) else ():
            if isinstance(item, Mapping) and len(item) == 1:
                ((label, opts),) = item.items()
            else:
                label, opts = item, None
            opts = dict(opts) if isinstance(opts, Mapping) else {}
            base = opts.get(self.base_key, label)
            if isinstance(base, str) and base in self.registry:
                out.append((str(label), self.registry[base].options, opts))
        return out


class _OptionsBase(BaseModel):
    """Base of a derived options model: finite numbers, frozen, and a stray key refused with
    the list of the valid ones (and the closest)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _no_stray_keys(cls, data):
        if isinstance(data, Mapping):
            valid = list(cls.model_fields)
            for key in data:
                if key not in valid:
                    raise ValueError(
                        f"unknown option {key!r} of {cls.__doc__}; valid: "
                        f"{', '.join(valid) or '(none)'}{did_you_mean(key, valid)}"
                    )
        return data


def _description(info: dict) -> str | None:
    doc = info.get("doc")
    unit = info.get("unit")
    if doc and unit:
        return f"{doc} ({unit})"
    return doc or None


@functools.cache
def options_model(options_cls: type, name: str | None = None) -> type[BaseModel]:
    """A pydantic model of an options dataclass, from :func:`simlunar.registry.option_info`.

    Parameters
    ----------
    options_cls : dataclass type
        Fields declared with :func:`simlunar.registry.option`.
    name : str, optional
        What the options belong to (the stray-key message names it); default the class name.

    Returns
    -------
    type[pydantic.BaseModel]
        One field per dataclass field: its type (``choices`` become a ``Literal``), its
        default, bounds ``ge``/``gt``/``le``/``lt`` and ``description`` (the option's doc and
        unit); a key that is not a field is a ``ValueError`` listing the valid keys.
    """
    if not dataclasses.is_dataclass(options_cls):
        raise TypeError(f"options_model takes an options dataclass, got {options_cls!r}")
    hints = typing.get_type_hints(options_cls)
    fields: dict[str, Any] = {}
    for fname, info in option_info(options_cls).items():
        ann = hints.get(fname, Any)
        if info.get("choices") is not None:
            ann = Literal[tuple(info["choices"])]
        bounds = {k: info[k] for k in ("ge", "gt", "le", "lt") if info.get(k) is not None}
        if info.get("file") is not None:  # the marker the cache key's file walk reads
            ann = Annotated[ann, info["file"]]
        default = info["default"]
        if default is dataclasses.MISSING:
            fields[fname] = (ann, Field(..., description=_description(info), **bounds))
        else:
            fields[fname] = (ann, Field(default, description=_description(info), **bounds))
    label = name or options_cls.__name__
    return create_model(
        f"{options_cls.__name__}Cfg", __base__=_OptionsBase, __doc__=label, **fields
    )


def validate_options(options_cls: type, values: Mapping | None, *, name: str | None = None):
    """The keys of ``values`` that were given, validated by :func:`options_model` (types,
    bounds, choices, no stray key) and then by the options class itself; a plain dict.

    Raises
    ------
    ValueError
        (pydantic's ``ValidationError`` is one) naming the key and the rule it breaks.
    """
    model = options_model(options_cls, name)
    cfg = model.model_validate(dict(values or {}))
    plain = cfg.model_dump(exclude_unset=True)
    options_cls(**plain)  # the library's own check (a rule across fields, if any)
    return plain


def reconstruction_specs(value) -> list:
    """``study.reconstructions`` validated: a list whose items are a name of
    :data:`simlunar.reconstruction.RECONSTRUCTIONS` or a one-key mapping ``{name: {options}}``,
    the options validated by the schema derived from the entry's options class.

    Returns the plain list with each item as given, a mapping with no option left as its name
    (``{linear: {}}`` is ``linear``), so the default ``[linear]`` is one value.
    """
    if isinstance(value, (str, Mapping)):
        value = [value]
    if not isinstance(value, (list, tuple)) or not value:
        raise ValueError(
            f"must be a non-empty list of reconstruction names or {{name: {{options}}}} "
            f"mappings, got {value!r}"
        )
    out, seen = [], []
    for item in value:
        spec = ReconstructionSpec.parse(item)
        name, base = spec.label, spec.name
        # {label: {reconstruction: <name>, options}}: a registered reconstruction under a label
        # of its own (the same one twice with other options, e.g. with and without a frame)
        if spec.labelled and name in RECONSTRUCTIONS:
            raise ValueError(f"label {name!r}: a new name, not another reconstruction's")
        if base not in RECONSTRUCTIONS:
            valid = ", ".join(RECONSTRUCTIONS.names())
            raise ValueError(
                f"unknown reconstruction {base!r}; valid: {valid}"
                f"{did_you_mean(str(base), RECONSTRUCTIONS.names())}"
            )
        if name in seen:
            raise ValueError(f"reconstruction {name!r} is listed twice")
        seen.append(name)
        plain = validate_options(
            RECONSTRUCTIONS[base].options, spec.options, name=f"reconstruction {name}"
        )
        out.append(ReconstructionSpec(name, base, plain).item())
    return out


def reconstruction_mapping(specs) -> dict:
    """``{label: options dict}`` of a validated :func:`reconstruction_specs` list, in order
    (a labelled item's dict names its ``reconstruction``)."""
    return {spec.label: spec.values() for spec in parse_reconstructions(specs)}
