"""Registries of named components: one entry per component, carrying its options class.

A component (a reconstruction, a planner, a coding, a BSDF, ...) is registered once, as
``name -> (callable or class, OptionsClass)``. Everything else derives from that entry: the
name check (an unknown name is a ``ValueError`` that lists the valid names and suggests the
closest), the stray-key check of its options (:func:`build_options`), and the option bounds
(declared once with :func:`option`, checked by :func:`check_bounds` in the options class's
``__post_init__`` and read by ``config/`` to derive the YAML schema).

The options class is a small frozen dataclass that lives beside the code that reads it, derived
from :class:`Options` (whose ``__post_init__`` runs :func:`check_bounds`).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import numbers
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = [
    "Entry",
    "FileOption",
    "Options",
    "Registry",
    "UnknownNameError",
    "build_options",
    "check_bounds",
    "did_you_mean",
    "did_you_mean_file",
    "file_option",
    "option",
    "option_docs",
    "option_info",
    "shared_option",
]


def _closest(name: str, valid) -> list[str]:
    """The valid names closest to ``name`` (all of those equally close), by difflib's ratio
    (at least 0.6); empty when none is close."""
    valid = list(dict.fromkeys(str(v) for v in valid))
    ratio = {v: difflib.SequenceMatcher(None, str(name), v).ratio() for v in valid}
    best = max(ratio.values(), default=0.0)
    return [v for v in valid if ratio[v] == best] if best >= 0.6 else []


def _hint(close: list[str]) -> str:
    if not close:
        return ""
    shown = [repr(c) for c in close]
    text = shown[0] if len(shown) == 1 else f"{', '.join(shown[:-1])} or {shown[-1]}"
    return f" (did you mean {text}?)"


def did_you_mean(name: str, valid) -> str:
    """`` (did you mean 'x'?)`` for the closest valid name, or an empty string.

    Names equally close are all given (``'aerial_l'`` is as close to ``aerial_1`` as to
    ``aerial_2``: `` (did you mean 'aerial_1', 'aerial_2' or 'aerial_3'?)``), never one of
    them picked by its spelling. Closeness is difflib's ratio, at least 0.6.
    """
    return _hint(_closest(name, valid))


def did_you_mean_file(path) -> str:
    """`` (did you mean 'dir/x.yaml'?)`` for the closest existing files (by name) of the
    folder of a missing ``path`` with the same suffix, or an empty string."""
    p = Path(path)
    try:
        siblings = sorted(q.name for q in p.parent.glob(f"*{p.suffix}") if q.is_file())
    except OSError:
        return ""
    return _hint([str(p.parent / c) for c in _closest(p.name, siblings)])


class UnknownNameError(ValueError, KeyError):
    """An unknown component or option name (a ``ValueError``; a ``KeyError`` too, so that a
    registry behaves as a mapping)."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


@dataclass(frozen=True)
class FileOption:
    """Marks an option (or a YAML field) whose value names a file a unit reads.

    Declared once, where the option is (``option(..., file="model")`` in an options class,
    ``Annotated[Path | None, FileOption("dem")]`` in a hand-written config model); the unit's
    cache key hashes the bytes of every such file, found by walking the declarations
    (:func:`simlunar.pipeline.inputs.input_files`), so a file replaced at the same path is
    another input. ``kind`` says which files come with it: ``model`` (a ``.joblib`` and its
    ``.json`` record beside it), ``dem`` and ``albedo`` (a grid and the files GDAL reads with
    it), ``preset`` (a preset name, the YAML it resolves to).
    """

    kind: str
    #: a model's record format (``simlunar-learned-map/1``): a model file of another format
    #: (a map's model named as a reconstruction's) is refused before any work
    format: str | None = None


def file_option(info_or_field) -> FileOption | None:
    """The :class:`FileOption` of a dataclass field, a pydantic ``FieldInfo`` or an
    :func:`option_info` row, or None when the option names no file."""
    meta = getattr(info_or_field, "metadata", None)
    if isinstance(info_or_field, Mapping):  # an option_info row
        return info_or_field.get("file")
    if isinstance(meta, Mapping):  # a dataclass field
        return meta.get("file")
    for m in meta or ():  # a pydantic FieldInfo: the Annotated metadata
        if isinstance(m, FileOption):
            return m
    return None


def option(
    default: Any = dataclasses.MISSING,
    *,
    doc: str,
    unit: str | None = None,
    ge: float | None = None,
    gt: float | None = None,
    le: float | None = None,
    lt: float | None = None,
    choices: tuple | None = None,
    key_unit: str | None = None,
    file: str | FileOption | None = None,
    default_factory: Callable[[], Any] | Any = dataclasses.MISSING,
):
    """A dataclass field with its documentation, unit and bounds written once.

    ``unit`` is the SI unit of the library value; ``key_unit`` the unit its YAML key is
    written in where that is not ``unit`` (``"ns"`` for a field in ``"s"``: the key
    ``fwhm_s`` becomes ``fwhm_ns``, its default and bounds converted by ``config/``, which
    knows the factor). ``ge``/``gt``/``le``/``lt`` are inclusive / exclusive bounds (of each
    element of a tuple) and ``choices`` the allowed values, checked by :func:`check_bounds`.
    ``file`` marks an option whose value names a file a unit reads, by kind
    (:class:`FileOption`): its bytes go into the unit's cache key.
    """
    meta = {"doc": doc, "unit": unit, "ge": ge, "gt": gt, "le": le, "lt": lt, "choices": choices,
            "key_unit": key_unit}  # fmt: skip
    if file is not None:
        meta["file"] = file if isinstance(file, FileOption) else FileOption(file)
    if default_factory is not dataclasses.MISSING:
        return field(default_factory=default_factory, metadata=meta)
    return field(default=default, metadata=meta)


def shared_option(table: Mapping[str, Mapping[str, Any]], name: str):
    """A fresh :func:`option` field from ``table[name]``: the keywords of :func:`option`, with
    ``default`` its first argument. For an option that several options classes declare alike
    (one table entry; each class gets its own field).

    Raises
    ------
    KeyError
        ``name`` is not in ``table``.
    """
    spec = dict(table[name])
    return option(spec.pop("default"), **spec)


def option_info(options_cls) -> dict[str, dict]:
    """name -> {"default", "doc", "unit", "ge", "gt", "le", "lt", "choices", "key_unit", "file",
    "type"} of each field of an options dataclass (the input of the derived YAML schema and docs)."""
    out = {}
    for f in dataclasses.fields(options_cls):
        if f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            default = dataclasses.MISSING
        keys = ("doc", "unit", "ge", "gt", "le", "lt", "choices", "key_unit", "file")
        meta = {k: f.metadata.get(k) for k in keys}
        out[f.name] = {"default": default, "type": f.type, **meta}
    return out


#: the bound keywords of :func:`option` and the relation each states
_SIGNS = {"ge": ">=", "gt": ">", "le": "<=", "lt": "<"}


def _bounds_text(info: dict) -> str:
    """``>= 0, < 1`` from an :func:`option_info` row (empty without bounds)."""
    parts = [f"{_SIGNS[k]} {info[k]:g}" for k in _SIGNS if info.get(k) is not None]
    if info.get("choices") is not None:
        parts.append("one of " + ", ".join(map(repr, info["choices"])))
    return ", ".join(parts)


def _sentence(text: str) -> str:
    """``text`` as a sentence: a leading lowercase word capitalised (a symbol such as ``k``,
    ``lam_t`` or ``dz/dx`` kept as written) and a full stop at the end."""
    first = text.split(maxsplit=1)[0].rstrip(",:;.")
    if first.isalpha() and first.islower() and (len(first) > 1 or first == "a"):
        text = text[0].upper() + text[1:]
    return text if text.endswith(".") else text + "."


def option_docs(options_cls) -> list[str]:
    """A numpydoc ``Attributes`` section, one entry per field of an options dataclass, from
    the metadata :func:`option` wrote (doc, unit, bounds) and the default; empty when no field
    was declared with :func:`option`. The API reference appends it to the class's docstring,
    so a field is documented where it is declared, and only there.

    Examples
    --------
    ``shadow: float = option(0.02, doc="shadowed below this", ge=0, lt=1)`` gives::

        shadow : float, default 0.02
            Shadowed below this. >= 0, < 1.
    """
    info = option_info(options_cls)
    if not any(row["doc"] for row in info.values()):
        return []
    lines = ["Attributes", "----------"]
    for name, row in info.items():
        kind = row["type"] if isinstance(row["type"], str) else getattr(row["type"], "__name__", "")
        head = f"{name} : {kind}" if kind else name
        default = row["default"]
        if default is not dataclasses.MISSING and not dataclasses.is_dataclass(default):
            head += f", default {default!r}"
        lines.append(head)
        unit = f"unit {row['unit']}" if row["unit"] else ""
        extra = ", ".join(x for x in (unit, _bounds_text(row)) if x)
        text = " ".join(_sentence(x) for x in (row["doc"], extra) if x)
        if text:
            lines.append(f"    {text}")
    return lines


def _optional(f) -> bool:
    """Whether a field may hold None: its default is None or its annotation names None."""
    return f.default is None or "None" in str(f.type) or "Optional" in str(f.type)


def check_bounds(obj) -> None:
    """Check every field of an options dataclass against the bounds declared by
    :func:`option`; a ``ValueError`` naming the field, its value and the rule. None passes
    the bounds of a field that may hold it (default None, or ``| None`` in its annotation)
    and fails them elsewhere; the bounds of a tuple hold for each of its elements."""
    for f in dataclasses.fields(obj):
        m = f.metadata
        v = getattr(obj, f.name)
        if m.get("choices") is not None and v not in m["choices"]:
            valid = ", ".join(map(repr, m["choices"]))
            hint = did_you_mean(v, m["choices"])
            raise ValueError(f"{f.name} must be one of {valid}, got {v!r}{hint}")
        rules = [(k, m.get(k)) for k in _SIGNS if m.get(k) is not None]
        if not rules or (v is None and _optional(f)):
            continue
        for x in v if isinstance(v, tuple) else (v,):
            if isinstance(x, bool) or not isinstance(x, numbers.Real) or not math.isfinite(x):
                raise ValueError(f"{f.name} must be a finite number, got {v!r}")
            for k, bound in rules:
                ok = {"ge": x >= bound, "gt": x > bound, "le": x <= bound, "lt": x < bound}[k]
                if not ok:
                    each = " each" if isinstance(v, tuple) else ""
                    raise ValueError(f"{f.name} must be{each} {_SIGNS[k]} {bound:g}, got {v!r}")


class Options:
    """Base of an options dataclass: constructing one checks every field against the bounds
    its :func:`option` declares (:func:`check_bounds`).

    A subclass with a rule across fields extends ``__post_init__`` and calls
    ``super().__post_init__()`` first, so a value out of its own bounds is named before a rule
    that reads it (:class:`simlunar.reconstruction._reading.ReadingChecks` adds the share
    band's ``share_lo < share_hi`` this way).
    """

    __slots__ = ()

    def __post_init__(self) -> None:
        check_bounds(self)


@dataclass(frozen=True)
class Entry:
    """One registered component: its name, what runs it and its options class."""

    name: str
    target: Any
    options: type
    summary: str = ""
    meta: Mapping[str, Any] = field(default_factory=dict)

    def make_options(self, values: Mapping[str, Any] | None = None):
        """The options object from plain values (see :func:`build_options`)."""
        return build_options(self.options, values, what=self.name)


def build_options(options_cls, values: Mapping[str, Any] | None = None, *, what: str = ""):
    """``options_cls(**values)`` after checking every key is one of its fields.

    A stray key is a ``ValueError`` naming it, the valid keys and the closest one; bounds are
    the class's own (its ``__post_init__``).
    """
    values = dict(values or {})
    names = [f.name for f in dataclasses.fields(options_cls)]
    for key in values:
        if key not in names:
            where = f" of {what}" if what else ""
            raise UnknownNameError(
                f"unknown option {key!r}{where}; valid: {', '.join(names) or '(none)'}"
                f"{did_you_mean(key, names)}"
            )
    return options_cls(**values)


class Registry(Mapping):
    """``name -> Entry`` of one kind of component (``Registry("reconstruction")``).

    ``registry[name]`` raises :class:`UnknownNameError` (a ``ValueError``) listing the valid
    names and the closest one; ``name in registry`` and iteration work as for a dict.
    """

    def __init__(self, kind: str):
        self.kind = kind
        self._entries: dict[str, Entry] = {}

    def register(self, name: str, target: Any, options: type, *, summary: str = "", **meta):
        """Add one component; a name registered twice is an error (one entry per name)."""
        if name in self._entries:
            raise ValueError(f"{self.kind} {name!r} is registered twice")
        if not dataclasses.is_dataclass(options):
            raise TypeError(f"{self.kind} {name!r}: options must be a dataclass, got {options!r}")
        entry = Entry(name, target, options, summary, dict(meta))
        self._entries[name] = entry
        return entry

    def resolve(self, name: str, options=None) -> tuple[Entry, Any]:
        """The entry ``name`` and its options object from an instance, a mapping or None.

        A mapping (or None: the defaults) is built with :meth:`Entry.make_options`; an instance
        of another class is a ``TypeError`` naming both classes.
        """
        entry = self[name]
        if options is None or isinstance(options, dict):
            options = entry.make_options(options)
        elif not isinstance(options, entry.options):
            raise TypeError(
                f"{self.kind} {name!r} takes {entry.options.__name__}, got {type(options).__name__}"
            )
        return entry, options

    def __getitem__(self, name: str) -> Entry:
        try:
            return self._entries[name]
        except (KeyError, TypeError):
            raise UnknownNameError(
                f"unknown {self.kind} {name!r}; valid: {', '.join(self._entries)}"
                f"{did_you_mean(name, self._entries)}"
            ) from None

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def names(self) -> tuple[str, ...]:
        return tuple(self._entries)
