"""Scene description files for ``simlunar render SCENE.yaml --out DIR``.

A scene YAML is ``{name, description, terrain, render, seed}``: an experiment's ``terrain`` and
``render`` sections (the same models, :class:`~simlunar.config.terrain.TerrainCfg` and
:class:`~simlunar.config.render.RenderCfg`, so the same keys and bounds) without a study. Keys
carry unit suffixes (``_deg``, ``_m``); unknown keys are errors. ``render.sensor`` (default: the
experiment's sensor) also writes the noisy sensor image; ``sensor: null`` skips it.

The same ``seed`` gives the same terrain as an experiment with that seed (the per-stage seed
split of :func:`simlunar.pipeline.unit.stage_seeds`).
"""

from __future__ import annotations

from pathlib import Path

from pydantic import Field

from simlunar.config.fields import _Model
from simlunar.config.loading import resolve_terrain_files
from simlunar.config.messages import validate_file_data
from simlunar.config.render import RenderCfg
from simlunar.config.terrain import TerrainCfg
from simlunar.config.yamlio import load_yaml
from simlunar.errors import ConfigError

__all__ = ["SceneCfg", "load_scene"]


class SceneCfg(_Model):
    """One rendered view: terrain, camera, light, BSDF and sampling."""

    name: str = Field("scene", pattern=r"^[A-Za-z0-9_.-]+$")
    description: str = ""
    terrain: TerrainCfg
    render: RenderCfg = Field(default_factory=RenderCfg)
    seed: int = Field(0, ge=0, lt=2**31)


def load_scene(path) -> SceneCfg:
    """Read and validate a scene YAML; DEM paths are taken relative to the YAML's folder.

    Raises
    ------
    FileNotFoundError
        The YAML (or a DEM / albedo file it names) does not exist.
    ConfigError
        Invalid YAML or an invalid key (the message names the key path).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"scene file not found: {path}")
    data = load_yaml(path)
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: <root>: expected a mapping of keys, got {type(data).__name__}")
    cfg = validate_file_data(SceneCfg, data, path)
    return resolve_terrain_files(cfg, path.parent)
