"""Name checks against the components' own registries (presets, strategies, metrics).

The config is validated before anything runs, so a misspelt strategy fails in a second with
the key path instead of after a ten-minute render. The names come from the components
themselves (never a copy kept here), so a new strategy is usable as soon as it is registered.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

from simlunar.config.terrain import preset_names as names
from simlunar.errors import ConfigError
from simlunar.metrics import METRICS
from simlunar.planner import MEASURING, ORACLES, STRATEGIES
from simlunar.registry import did_you_mean, did_you_mean_file
from simlunar.scanner.rescan import SCAN_PLANNERS
from simlunar.sensors.structured_light import MODES

__all__ = [
    "check_metric",
    "check_preset",
    "check_scan_mode",
    "check_scan_planner",
    "check_strategy",
    "metric_names",
    "preset_names",
    "strategy_names",
]


def _check(name: str, valid: Iterable[str], path: str, what: str) -> None:
    valid = sorted(set(valid))
    if name not in valid:
        raise ConfigError(
            f"{path}: unknown {what} {name!r} (valid: {', '.join(valid)})"
            f"{did_you_mean(name, valid)}"
        )


def preset_names() -> list[str]:
    """Terrain preset names (``scenes/*.yaml`` via :mod:`simlunar.terrain.presets`)."""

    return list(names())


def check_preset(name: str, path: str) -> None:
    if Path(name).suffix in (".yaml", ".yml"):
        if not Path(name).is_file():
            raise ConfigError(f"{path}: preset file not found: {name}{did_you_mean_file(name)}")
        return
    _check(name, preset_names(), path, "terrain preset")


def strategy_names() -> list[str]:
    """Strategies of a sampling study: the planner's, the oracles (they read the truth, the
    study gives it to them only) and the measuring ones (``sequential``)."""
    return [*STRATEGIES, *MEASURING]


def check_strategy(name: str, path: str, options: Mapping | None = None) -> None:
    """A registered strategy, or a label whose ``options[name].strategy`` is one.

    Labels let one study compare variants of a strategy, e.g.
    ``strategy_options: {wavelet_bn: {strategy: wavelet, blue_noise: true}}``.
    ``options`` maps labels to :class:`~simlunar.config.schema.StrategyOptionsCfg`.
    """
    label_opts = (options or {}).get(name)
    base = getattr(label_opts, "strategy", None)
    if base is not None:
        _check(str(base), strategy_names(), f"{path} ({name}).strategy", "strategy")
        return
    _check(name, strategy_names(), path, "strategy")


def check_scan_planner(name: str, path: str) -> None:
    """A planner of the scanner study: a registered strategy that plans from the guide image
    alone (not an ``oracle_*``, which reads the truth, nor ``sequential``, which asks a sensor
    back) or one of :data:`simlunar.scanner.rescan.SCAN_PLANNERS` (it ranks the gray-code scan)."""
    if name in ORACLES or name in MEASURING:
        raise ConfigError(
            f"{path}: {name!r} is a planner of the sampling study only (the scanner study "
            "gives no planner the truth or a sensor to ask back)"
        )
    image_only = [s for s in STRATEGIES if s not in ORACLES and s not in MEASURING]
    _check(name, [*image_only, *SCAN_PLANNERS], path, "planner")


def metric_names() -> list[str]:
    return list(METRICS)


def check_metric(name: str, path: str) -> None:
    _check(name, metric_names(), path, "metric")


def check_scan_mode(name: str, path: str) -> None:

    _check(name, list(MODES), path, "scan mode")
