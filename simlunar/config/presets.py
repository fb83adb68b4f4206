"""Terrain preset files (``scenes/<name>.yaml``) read through the schema's models.

A preset file is a :class:`~simlunar.config.schema.TerrainPresetCfg`; an experiment's
``terrain.overrides`` (a :class:`~simlunar.config.schema.TerrainOverridesCfg`) is deep-merged
into it before validation, so the rules are the same models' either way.
:func:`simlunar.config.translate.terrain_params` turns the result into the terrain package's
:class:`~simlunar.terrain.params.TerrainParams`.
"""

from __future__ import annotations

import functools
from pathlib import Path

from pydantic import ValidationError

from simlunar.config.terrain import TerrainOverridesCfg, TerrainPresetCfg
from simlunar.errors import ConfigError


class PresetError(ValueError):
    """An invalid preset or override: ``key`` is the key path inside the preset (or None when
    the preset itself, not an override, is at fault: unknown name, unreadable file)."""

    def __init__(self, key: str | None, problem: str):
        super().__init__(f"{key}: {problem}" if key else problem)
        self.key = key
        self.problem = problem


def preset_path(name: str) -> Path:
    """The YAML file of a preset name (``aerial_1``) or path (``my/preset.yaml``)."""
    from simlunar.terrain.presets import SCENES, preset_names

    looks_like_path = name.endswith((".yaml", ".yml")) or "/" in name or "\\" in name
    path = Path(name) if looks_like_path else SCENES / f"{name}.yaml"
    if not path.is_file():
        if looks_like_path:
            raise PresetError(None, f"terrain preset file not found: {path}")
        raise PresetError(
            None, f"unknown terrain preset {name!r} (valid: {', '.join(preset_names())})"
        )
    return path


@functools.lru_cache(maxsize=64)
def _read(path: Path, mtime_ns: int, size: int) -> dict:
    from simlunar.config.loading import load_yaml

    try:
        data = load_yaml(path)
    except ConfigError as exc:
        raise PresetError(None, str(exc)) from None
    if not isinstance(data, dict):
        raise PresetError(None, f"{path}: <root>: expected a mapping of keys")
    return data


def preset_data(name: str) -> dict:
    """The parsed YAML mapping of a preset (cached by path, modification time and size)."""
    path = preset_path(name)
    st = path.stat()
    return _read(path.resolve(), st.st_mtime_ns, st.st_size)


def _merge(data: dict, overrides: dict) -> dict:
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in data.items()}
    for sec, sub in overrides.items():
        merged = dict(out.get(sec) or {})
        merged.update(sub)
        out[sec] = merged
    return out


def merged_preset(name: str, overrides: TerrainOverridesCfg | None = None) -> TerrainPresetCfg:
    """A preset with ``overrides`` deep-merged in, validated.

    Raises
    ------
    PresetError
        ``key`` = the override's key path (``fractal.rms_m``) when an override makes the preset
        invalid; ``key`` None with a message naming the file when the preset itself is invalid.
    """
    from simlunar.config.loading import format_validation_error

    data = preset_data(name)
    try:
        base = TerrainPresetCfg.model_validate(data)
    except ValidationError as exc:
        raise PresetError(
            None, f"{preset_path(name)}: {format_validation_error(exc, data)}"
        ) from None
    ov = overrides.as_mapping() if overrides is not None else {}
    if not ov:
        return base
    merged = _merge(data, ov)
    try:
        return TerrainPresetCfg.model_validate(merged)
    except ValidationError as exc:
        line = format_validation_error(exc, merged)
        key, _, problem = line.partition(": ")
        return_key = key if key.split(".")[0] in ov else None
        raise PresetError(return_key, problem if return_key else line) from None
