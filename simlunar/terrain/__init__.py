"""Procedural lunar terrain and DEM I/O (NumPy/SciPy only).

``generate("aerial_1", rng=0)`` -> :class:`TerrainResult` (terrain, craters, rocks); presets in
``scenes/`` via :func:`load_preset`; files through :mod:`simlunar.terrain.io`.
"""

from simlunar.terrain.craters import Crater
from simlunar.terrain.generate import TerrainResult, generate, make_albedo
from simlunar.terrain.params import TerrainParams, params_from_dict
from simlunar.terrain.presets import load_preset, preset_names
from simlunar.terrain.rocks import Rock
from simlunar.terrain.types import Terrain

__all__ = [
    "Crater",
    "Rock",
    "Terrain",
    "TerrainParams",
    "TerrainResult",
    "generate",
    "load_preset",
    "make_albedo",
    "params_from_dict",
    "preset_names",
]
