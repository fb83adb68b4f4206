"""One item of ``study.reconstructions``, read in one place: its label, its reconstruction,
its options.

An item is a registered name (``linear``), a one-key mapping ``{name: {options}}``, or a
labelled one ``{label: {reconstruction: name, options}}`` (a registered reconstruction under a
label of its own: the same one twice with other options). :meth:`ReconstructionSpec.parse` is
the one reader of that shape: the schema's validation, the translation into the studies'
options, the protocol, the guide's "is one guided" check, the order of rows, the aggregation
and the cache key's method versions all read an item through it. Plain Python only (a result
folder is read without the scientific stack): the names are checked against
:data:`simlunar.reconstruction.RECONSTRUCTIONS` where the registry is at hand.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = ["ReconstructionSpec", "parse_reconstructions"]


@dataclass(frozen=True)
class ReconstructionSpec:
    """One configured reconstruction.

    Attributes
    ----------
    label : str
        The name its rows, tables and figures carry (the item's name or its key).
    name : str
        The registered reconstruction it runs (``label`` unless the item names another in
        ``reconstruction``).
    options : mapping
        The option values the item gives (the ``reconstruction`` key left out); empty: the
        options class's defaults.
    """

    label: str
    name: str
    options: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def parse(cls, item) -> ReconstructionSpec:
        """The spec of one item: a name, ``{name: options or None}`` or
        ``{label: {reconstruction: name, options}}``.

        Raises
        ------
        ValueError
            A mapping of more than one key, options that are not a mapping, or a label or
            name that is not a non-empty string.
        """
        if isinstance(item, Mapping):
            if len(item) != 1:
                raise ValueError(
                    f"an item is one name or one {{name: {{options}}}} mapping, got {dict(item)}"
                )
            label, opts = next(iter(item.items()))
        else:
            label, opts = item, None
        if opts is not None and not isinstance(opts, Mapping):
            raise ValueError(f"{label}: options must be a mapping, got {opts!r}")
        values = dict(opts or {})
        name = values.pop("reconstruction", label)
        if not isinstance(label, str) or not label:
            raise ValueError(f"label {label!r}: a reconstruction's label is a non-empty name")
        if not isinstance(name, str) or not name:
            raise ValueError(f"unknown reconstruction {name!r} (label {label!r}): not a name")
        return cls(label, name, values)

    @property
    def labelled(self) -> bool:
        """Whether the item runs a registered reconstruction under a label of its own."""
        return self.label != self.name

    def values(self) -> dict:
        """The item's mapping of options, with ``reconstruction`` for a labelled one (what
        the studies' ``reconstructions`` options take: ``{label: values}``)."""
        return (
            {"reconstruction": self.name, **self.options} if self.labelled else dict(self.options)
        )

    def item(self):
        """The item as written: the name alone when it gives no option."""
        values = self.values()
        return {self.label: values} if values else self.label


def parse_reconstructions(items: Iterable | None) -> list[ReconstructionSpec]:
    """The specs of a ``study.reconstructions`` list (None or empty: none), in order."""
    return [ReconstructionSpec.parse(item) for item in items or ()]
