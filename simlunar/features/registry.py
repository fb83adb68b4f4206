"""The registry of importance maps: ``name -> (map function, options class)``.

A map is a function ``fn(image, **options) -> (rows, cols) float64 map >= 0`` registered once
in :data:`MAPS` with its frozen options class (fields declared with
:func:`simlunar.registry.option`); :func:`feature_map` runs it by name. The planners
(:mod:`simlunar.planner`), the YAML schema of ``feature_opts`` and the translation derive
from the entries: a new map is its module, one registration line
(:mod:`simlunar.features`) and, for a planner of its own, one planner line.

Entry metadata: ``needs_model`` (a trained model file: options ``model`` and ``density``,
the plan's k / N, both required), ``label`` (display name of the planner of the same name).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from simlunar.registry import Registry, UnknownNameError, did_you_mean

__all__ = [
    "MAPS",
    "NoMapOptions",
    "feature_map",
    "image_maps",
    "map_options",
]

#: map name -> Entry(function, options class); the entries are registered by
#: :mod:`simlunar.features`, which imports each map's module
MAPS = Registry("map")


@dataclass(frozen=True)
class NoMapOptions:
    """Options of a map that takes none (gradient, saliency)."""


def image_maps() -> tuple[str, ...]:
    """The maps computed from the image alone (no trained model), in registration order."""
    return tuple(n for n, e in MAPS.items() if not e.meta.get("needs_model"))


def map_options(name: str) -> tuple[str, ...]:
    """The option names of map ``name`` (the fields of its options class)."""
    return tuple(f.name for f in dataclasses.fields(MAPS[name].options))


def feature_map(name: str, image, **opts) -> np.ndarray:
    """Compute the importance map ``name`` of ``image``.

    Parameters
    ----------
    name : str
        A name of :data:`MAPS` (an unknown one is a ``ValueError`` listing them).
    image : ndarray, shape (rows, cols) or (rows, cols, 3)
        Guide image (linear radiance or any intensity scale); must be finite.
    **opts
        Options of the chosen map: the fields of its options class (e.g. ``size``/``scale``
        for entropy, ``levels`` for wavelet); a stray key is a ``ValueError`` naming the
        valid ones. A map of a trained model (``needs_model``) needs ``model`` (a
        ``.joblib`` path) and ``density`` (k / N).

    Returns
    -------
    ndarray of float64, shape (rows, cols), >= 0
    """
    if not isinstance(name, str) or name not in MAPS:
        raise UnknownNameError(
            f"unknown feature {name!r}; valid: {', '.join(MAPS)}"
            + (did_you_mean(name, MAPS.names()) if isinstance(name, str) else "")
        )
    entry, options = MAPS.resolve(name, dict(opts))
    values = {f.name: getattr(options, f.name) for f in dataclasses.fields(options)}
    if entry.meta.get("needs_model"):
        missing = sorted(k for k in ("model", "density") if values.get(k) is None)
        if missing:
            raise ValueError(f"feature {name!r} needs option(s) {missing}")
    return entry.target(image, **values)
