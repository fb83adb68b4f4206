"""simlunar's Mitsuba plugins, one module per plugin (Mitsuba style).

Each module documents its plugin's parameters in a table and defines a ``register(mi)`` that
builds the plugin class (a subclass of ``mi.BSDF``, which exists only once a variant is set)
and registers it under its Mitsuba name; :func:`simlunar.render.backend.init` runs every
``register`` of :data:`PLUGINS` right after ``mi.set_variant``. Importing this package never
imports Mitsuba.

:data:`PLUGINS` is derived from this package's modules (every public module, keyed by its
``NAME``): a new BSDF's plugin is registered without an edit here. It is not read from the BSDF
registry (:data:`simlunar.render.materials.BSDFS`, whose ``meta["plugin"]`` names the same
modules, tests/render/test_plugins.py) because that registry builds Mitsuba textures, so it
imports the backend, which imports this package."""

from __future__ import annotations

import importlib
import pkgutil

__all__ = ["PLUGINS", "plugin_modules"]


def plugin_modules() -> dict:
    """Plugin name (the module's ``NAME``) -> module (each with ``register(mi)``): every module
    of this package whose name does not start with an underscore."""
    modules = (
        importlib.import_module(f"{__name__}.{info.name}")
        for info in pkgutil.iter_modules(__path__)
        if not info.name.startswith("_")
    )
    return {m.NAME: m for m in modules}


def __getattr__(name: str):
    # PLUGINS is computed on first use: the registry imports plugin modules (their specs)
    if name == "PLUGINS":
        return plugin_modules()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
