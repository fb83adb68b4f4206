"""Terrain presets: YAML files in ``scenes/`` (data files of the terrain package).

``load_preset("aerial_1")`` reads ``scenes/aerial_1.yaml``; a path to any YAML file works too.
``scale`` shrinks the grid with the same spacing (a smaller area with the same statistics per
square metre), so tests and quick renders stay cheap and cost scales with the number of cells.
"""

from __future__ import annotations

from pathlib import Path

from simlunar.terrain.params import TerrainParams, merge_overrides, params_from_dict

SCENES = Path(__file__).resolve().parents[2] / "scenes"


def preset_names() -> list[str]:
    """Names of the terrain presets shipped in ``scenes/`` (files with a ``grid`` section)."""
    import yaml

    out = []
    for p in sorted(SCENES.glob("*.yaml")):
        try:
            d = yaml.safe_load(p.read_text())
        except (OSError, yaml.YAMLError):
            continue
        if isinstance(d, dict) and "grid" in d and "craters" in d:
            out.append(p.stem)
    return out


def load_preset(
    name_or_path, *, scale: float = 1.0, overrides: dict | None = None
) -> TerrainParams:
    """Validated :class:`TerrainParams` from a preset name or a YAML file.

    Parameters
    ----------
    name_or_path : str or Path
        A preset name (``aerial_1``, ``aerial_2``, ``aerial_3``, ``moonyard``) or a YAML path.
    scale : float in (0, 1]
        Multiply rows and cols by ``scale`` (at least 16 each), keeping the spacing.
    overrides : dict, optional
        ``{section: {key: value}}`` deep-merged into the preset before validation, e.g.
        ``{"fractal": {"rms_m": 0.05}}`` (keys: :func:`simlunar.terrain.params.override_keys`).

    Raises
    ------
    ValueError
        Unknown preset (lists the valid names), unparsable YAML, or an invalid field (named,
        prefixed with the file).
    simlunar.terrain.params.ParamError
        An unknown override key or a bad override value: a ``ValueError`` whose ``key`` is the
        override's path (``fractal.rms_m``), not prefixed with the file.
    FileNotFoundError
        A path that does not exist.
    """
    import yaml

    s = str(name_or_path)
    looks_like_path = s.endswith((".yaml", ".yml")) or "/" in s or "\\" in s
    if looks_like_path:
        path = Path(s)
        if not path.is_file():
            raise FileNotFoundError(f"terrain preset file not found: {path}")
    else:
        path = SCENES / f"{s}.yaml"
        if not path.is_file():
            raise ValueError(f"unknown terrain preset {s!r}; valid: {', '.join(preset_names())}")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not valid YAML ({exc})") from None
    try:
        params = params_from_dict(data, where=str(path))
    except ValueError as exc:
        msg = str(exc)
        raise ValueError(msg if msg.startswith(str(path)) else f"{path}: {msg}") from None
    if overrides:
        # the preset itself is valid (above), so any error now comes from an override
        params = params_from_dict(merge_overrides(data, overrides), where="overrides")
    try:
        return params.scaled(scale)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
