"""The registries of planners and placements: one entry per component with its options class.

A **placement** (:data:`PLACEMENTS`) turns an importance map into k pixels:
``fn(weights, k, *, rng, options) -> flat indices``; ``random`` is the paper's weighted draw
(:mod:`simlunar.planner.draw`), ``lloyd`` the halftone + weighted Lloyd layout
(:func:`simlunar.planner.placement.lloyd_layout`).

A **planner** (:data:`PLANNERS`) is either a *map planner*, target :class:`MapSource`: a map of
:data:`simlunar.features.MAPS` (or the combination of maps) placed by a placement, so a planner
is named apart from its map (``wavelet_lloyd`` = map ``wavelet`` + placement ``lloyd``); or a
function ``fn(k, shape, rng, *, truth, options) -> flat indices`` (grid, random, the image-free
Lloyd layout, the oracles). Every entry carries its options class; a map planner's are its
placement's (a plan's ``placement`` option switches to another placement and its options),
plus ``feature_opts`` (the map's options class) and, for the combination, ``coefficients``.

Entry metadata: ``label`` (display name), ``truth`` (an oracle: reads the true depth, never
realisable), ``measuring`` (plans while it measures: :func:`simlunar.planner.plan_sequential`),
``section`` (the YAML key its options sit under, e.g. ``oracle``).

:func:`simlunar.planner.plan`, the YAML schema of planner options and their translation all
derive from these entries (:mod:`simlunar.config.planners`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from simlunar.features import MAPS
from simlunar.registry import Entry, Registry

__all__ = [
    "COMBINATION",
    "PLACEMENTS",
    "PLANNERS",
    "MapSource",
    "NoOptions",
    "combinable",
    "field_names",
    "map_of",
    "planner_label",
    "planner_options",
    "register_map_planner",
]

#: placement name -> Entry(``fn(weights, k, *, rng, options)``, options class)
PLACEMENTS = Registry("placement")
#: planner name -> Entry(MapSource or fn, options class); registered by :mod:`simlunar.planner`
PLANNERS = Registry("strategy")
#: the map source of the combination planner: a weighted sum of maps (``coefficients``)
COMBINATION = "combination"


@dataclass(frozen=True)
class NoOptions:
    """Options of a planner that takes none (grid, random)."""


@dataclass(frozen=True)
class MapSource:
    """The target of a map planner.

    Attributes
    ----------
    map : str
        A name of :data:`simlunar.features.MAPS`, or :data:`COMBINATION`.
    placement : str
        The default placement, a name of :data:`PLACEMENTS` (a plan's ``placement`` option
        overrides it).
    """

    map: str
    placement: str = "random"


def field_names(options_cls) -> tuple[str, ...]:
    """The field names of an options dataclass, in declaration order."""
    return tuple(f.name for f in dataclasses.fields(options_cls))


def register_map_planner(name: str, map_name: str, placement: str = "random", *, label=None):
    """Register planner ``name`` = map ``map_name`` placed by ``placement``.

    Its options class is the placement's; ``label`` (display name) defaults to the map's
    label, with the placement named when it is not the paper's random draw.
    """
    if map_name != COMBINATION:
        MAPS[map_name]  # an unknown map is an error here, at registration
    place = PLACEMENTS[placement]
    if label is None:
        base = MAPS[map_name].meta.get("label", map_name) if map_name in MAPS else map_name
        label = base if placement == "random" else f"{base}, {placement.capitalize()}"
    return PLANNERS.register(
        name, MapSource(map_name, placement), place.options, summary=label, label=label
    )


def map_of(name: str) -> str | None:
    """The map a planner samples (a :data:`~simlunar.features.MAPS` name or
    :data:`COMBINATION`), or None for a planner without one."""
    target = PLANNERS[name].target
    return target.map if isinstance(target, MapSource) else None


def combinable() -> tuple[str, ...]:
    """Maps a combination may weight: ``uniform`` (a constant map) and the maps registered
    with ``combine=True``."""
    return ("uniform", *(n for n, e in MAPS.items() if e.meta.get("combine")))


def planner_label(name: str) -> str:
    """Display name of a planner (paper spelling), for tables and legends."""
    return PLANNERS[name].meta.get("label", name)


def planner_options(name: str, placement: str | None = None) -> tuple[str, ...]:
    """The option names :func:`simlunar.planner.plan` accepts for planner ``name``.

    A map planner takes ``placement``, the options of ``placement`` (default: those of every
    placement, the set some placement accepts), ``feature_opts`` and, for the combination,
    ``coefficients``; a function planner the fields of its options class.
    """
    entry: Entry = PLANNERS[name]
    if not isinstance(entry.target, MapSource):
        return field_names(entry.options)
    places = [placement] if placement is not None else list(PLACEMENTS)
    keys = ["placement"]
    for p in places:
        keys += [k for k in field_names(PLACEMENTS[p].options) if k not in keys]
    keys.append("feature_opts")
    if entry.target.map == COMBINATION:
        keys.append("coefficients")
    return tuple(keys)
