"""simlunar's Mitsuba plugins, one module per plugin (Mitsuba style).

Each module documents its plugin's parameters in a table and defines a ``register(mi)`` that
builds the plugin class (a subclass of ``mi.BSDF``, which exists only once a variant is set)
and registers it under its Mitsuba name; :func:`simlunar.render.backend.init` runs every
``register`` of :data:`PLUGINS` right after ``mi.set_variant``. Importing this package never
imports Mitsuba.

==============  =========================================  ==================================
name            module                                     model
==============  =========================================  ==================================
``oren_nayar``  :mod:`simlunar.render.plugins.oren_nayar`  Oren-Nayar (1994) rough diffuse
``hapke``       :mod:`simlunar.render.plugins.hapke`       Hapke regolith BRDF
==============  =========================================  ==================================
"""

from __future__ import annotations

from simlunar.render.plugins import hapke, oren_nayar

__all__ = ["PLUGINS"]

#: plugin name -> module (each with ``register(mi)``)
PLUGINS = {"oren_nayar": oren_nayar, "hapke": hapke}
