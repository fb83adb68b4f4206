"""Procedural lunar terrain and DEM I/O (NumPy/SciPy only).

``generate(params, rng=0)`` -> :class:`TerrainResult` (terrain, craters, rocks) from
:class:`TerrainParams`; the presets in ``scenes/`` are read by ``simlunar.config``
(``simlunar.config.translate.preset_params("aerial_1")``); files through :mod:`simlunar.terrain.io`.
"""

from simlunar.terrain.craters import Crater
from simlunar.terrain.generate import TerrainResult, generate, make_albedo
from simlunar.terrain.params import TerrainParams
from simlunar.terrain.rocks import Rock
from simlunar.terrain.types import Terrain

__all__ = [
    "Crater",
    "Rock",
    "Terrain",
    "TerrainParams",
    "TerrainResult",
    "generate",
    "make_albedo",
]
