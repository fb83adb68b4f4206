"""Name checks against the components' own registries (presets, strategies, metrics).

The config is validated before anything runs, so a misspelt strategy fails in a second with
the key path instead of after a ten-minute render. The names come from the components
themselves (never a copy kept here), so a new strategy is usable as soon as it is registered.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from simlunar.errors import ConfigError


def _check(name: str, valid: Iterable[str], path: str, what: str) -> None:
    valid = sorted(set(valid))
    if name not in valid:
        raise ConfigError(f"{path}: unknown {what} {name!r} (valid: {', '.join(valid)})")


def preset_names() -> list[str]:
    """Terrain preset names (``scenes/*.yaml`` via :mod:`simlunar.terrain.presets`)."""
    from simlunar.terrain import presets

    for attr in ("list_presets", "preset_names", "available"):
        fn = getattr(presets, attr, None)
        if callable(fn):
            return list(fn())
    for attr in ("PRESETS",):
        reg = getattr(presets, attr, None)
        if reg is not None:
            return list(reg)
    scenes = Path(__file__).resolve().parents[2] / "scenes"
    return sorted(p.stem for p in scenes.glob("*.yaml"))


def check_preset(name: str, path: str) -> None:
    if Path(name).suffix in (".yaml", ".yml"):
        if not Path(name).is_file():
            raise ConfigError(f"{path}: preset file not found: {name}")
        return
    _check(name, preset_names(), path, "terrain preset")


def strategy_names() -> list[str]:
    from simlunar import planner

    for attr in ("STRATEGIES", "REGISTRY"):
        reg = getattr(planner, attr, None)
        if reg is not None:
            return list(reg)
    fn = getattr(planner, "strategy_names", None)
    return list(fn()) if callable(fn) else []


def check_strategy(name: str, path: str) -> None:
    _check(name, strategy_names(), path, "strategy")


def metric_names() -> list[str]:
    from simlunar import metrics

    for attr in ("METRICS", "REGISTRY"):
        reg = getattr(metrics, attr, None)
        if reg is not None:
            return list(reg)
    fn = getattr(metrics, "metric_names", None)
    return list(fn()) if callable(fn) else []


def check_metric(name: str, path: str) -> None:
    _check(name, metric_names(), path, "metric")


def check_scan_mode(name: str, path: str) -> None:
    from simlunar.scanner import modes

    _check(name, list(modes.MODES), path, "scan mode")
