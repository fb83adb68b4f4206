"""simlunar's Mitsuba plugins, one module per plugin (Mitsuba style).

Each module documents its plugin's parameters in a table and defines a ``register(mi)`` that
builds the plugin class (a subclass of ``mi.BSDF``, which exists only once a variant is set)
and registers it under its Mitsuba name; :func:`simlunar.render.backend.init` runs every
``register`` of :data:`PLUGINS` right after ``mi.set_variant``. Importing this package never
imports Mitsuba.

:data:`PLUGINS` is derived from the BSDF registry (:data:`simlunar.render.materials.BSDFS`,
each entry's ``meta["plugin"]``): a new BSDF's plugin is registered without an edit here.

================  =============================================  ==========================="""

from __future__ import annotations

import importlib

__all__ = ["PLUGINS", "plugin_modules"]


def plugin_modules() -> dict:
    """Plugin name -> module (each with ``register(mi)``), from the BSDF registry."""
    from simlunar.render.materials import BSDFS

    return {
        n: importlib.import_module(e.meta["plugin"])
        for n, e in BSDFS.items()
        if e.meta.get("plugin")
    }


def __getattr__(name: str):
    # PLUGINS is computed on first use: the registry imports plugin modules (their specs)
    if name == "PLUGINS":
        return plugin_modules()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
