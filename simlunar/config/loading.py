"""Loading and validating experiment YAMLs: one-line errors with key paths, sweeps, overrides.

The models are in :mod:`simlunar.config.schema` (re-exported here). Every problem is
reported as a :class:`simlunar.errors.ConfigError` whose one-line message names the key path
(``render.light.elevation_deg: ...``); see :func:`load_experiment`.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from simlunar.config import registry
from simlunar.config.lidar_checks import check_lidar_study
from simlunar.config.messages import (
    format_validation_error,
    is_label_mapping,
    model_at,
    valid_keys,
)
from simlunar.config.scanner import ScannerStudyCfg
from simlunar.config.schema import ExperimentCfg
from simlunar.config.studies import LidarStudyCfg, SamplingStudyCfg
from simlunar.config.yamlio import load_yaml
from simlunar.errors import ConfigError
from simlunar.registry import did_you_mean, did_you_mean_file

__all__ = [
    "apply_sweep_value",
    "check_key_path",
    "get_path",
    "load_experiment",
    "resolve_terrain_files",
    "set_path",
    "to_plain",
    "validate_data",
]


def get_path(data: dict, path: str) -> Any:
    cur: Any = data
    for part in path.split("."):
        if not isinstance(cur, dict) or part not in cur:
            return None
        cur = cur[part]
    return cur


def set_path(data: dict, path: str, value: Any) -> dict:
    """A deep copy of ``data`` with the dotted ``path`` set to ``value`` (parents created)."""
    out = copy.deepcopy(data)
    cur = out
    parts = path.split(".")
    for part in parts[:-1]:
        nxt = cur.get(part)
        if not isinstance(nxt, dict):
            nxt = {}
            cur[part] = nxt
        cur = nxt
    cur[parts[-1]] = value
    return out


def apply_sweep_value(data: dict, path: str, value: Any) -> dict:
    """``data`` with one sweep (or ``--set``) value applied.

    Setting a ``kind`` resets its section to that kind's defaults, because the other keys of
    the old kind (``elevation_deg`` of a sun) are not valid for the new one (a camera light).
    """
    parts = path.split(".")
    if parts[-1] == "kind" and len(parts) > 1:
        return set_path(data, ".".join(parts[:-1]), {"kind": value})
    return set_path(data, path, value)


def check_key_path(path: str, data: dict) -> None:
    """Raise ConfigError unless ``path`` names a settable key of the schema for this data
    (``terrain.overrides.fractal.rms_m`` included: the overrides are typed preset sections).

    A mapping with free labels (``study.strategy_options``) takes any label, whose value is
    checked when the whole experiment is validated, and the keys inside a label
    (``study.strategy_options.wavelet_lloyd.uniform_mix``) are checked like any other.
    """
    parts = path.split(".")
    parent = ".".join(parts[:-1])
    if parts[0] not in ("sweep", "name") and is_label_mapping(parent, data, ExperimentCfg):
        return
    try:
        keys = valid_keys(parent, data, ExperimentCfg)
        model = model_at(parent, data, ExperimentCfg)
    except ConfigError:
        keys, model = [], None
    held = get_path(data, parent) if parent else data
    if model is None and parent and held is not None and not isinstance(held, dict):
        # the key exists but holds a value, not a mapping: one key of it cannot be set
        raise ConfigError(
            f"sweep.{path}: {parent} is a {type(held).__name__} in this file, not a mapping of "
            f"keys; set it whole (--set {parent}=...)"
        )
    if model is None or parts[-1] not in keys:
        # name the keys of the deepest section of the path that exists
        hint = ""
        for n in range(len(parts) - 1, -1, -1):
            prefix = ".".join(parts[:n])
            try:
                keys = (
                    valid_keys(prefix, data, ExperimentCfg)
                    if model_at(prefix, data, ExperimentCfg) is not None
                    else []
                )
            except ConfigError:
                continue
            if keys:
                close = did_you_mean(parts[n], keys) if n < len(parts) else ""
                hint = f" (valid keys under {prefix or 'the root'}: {', '.join(keys)}){close}"
                break
        raise ConfigError(f"sweep.{path}: no such key in the experiment schema{hint}")
    if parts[0] in ("sweep", "name"):
        raise ConfigError(f"sweep.{path}: this key cannot be swept")


def validate_data(data: Any, *, base_dir: Path | None = None) -> ExperimentCfg:
    """Validate a parsed YAML mapping, including every sweep point and referenced files.

    Raises
    ------
    ConfigError
        One line naming the key path and the problem.
    """
    if not isinstance(data, dict):
        raise ConfigError(f"<root>: expected a mapping of keys, got {type(data).__name__}")
    try:
        cfg = ExperimentCfg.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(format_validation_error(exc, data, root=ExperimentCfg)) from None
    normalised: dict[str, list] = {}
    for path, values in cfg.sweep.items():
        check_key_path(path, data)
        if not values:
            raise ConfigError(f"sweep.{path}: give at least one value")
        normalised[path] = []
        for i, v in enumerate(values):
            point = apply_sweep_value({k: x for k, x in data.items() if k != "sweep"}, path, v)
            try:
                model = ExperimentCfg.model_validate(point)
            except ValidationError as exc:
                raise ConfigError(
                    f"sweep.{path}[{i}]: " + format_validation_error(exc, point, root=ExperimentCfg)
                ) from None
            normalised[path].append(_normalised_value(v, model, path))
    if normalised != cfg.sweep:
        cfg = cfg.model_copy(update={"sweep": normalised})
    cfg = resolve_terrain_files(cfg, base_dir)
    _check_registries(cfg, data)
    return cfg


def _has_text(v: Any) -> bool:
    if isinstance(v, str):
        return True
    return isinstance(v, list) and any(isinstance(x, str) for x in v)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _normalised_value(raw: Any, point: ExperimentCfg, path: str) -> Any:
    """A sweep value as the model holds it when the YAML gave text for a number
    (``"0.5 rad"`` -> 28.64..., ``"1/32"`` -> 0.03125); other values as written, so
    results.csv keeps ``30`` (not ``30.0``) in the column of a plain number."""
    if not _has_text(raw):
        return raw
    value = get_path(point.model_dump(mode="json", by_alias=True), path)
    if _is_number(value) or (isinstance(value, list) and value and all(map(_is_number, value))):
        return value
    return raw


def _check_registries(cfg: ExperimentCfg, data: dict) -> None:
    """Names that select code (preset, strategy, metric) must exist."""

    points = [cfg]
    for path, values in cfg.sweep.items():
        for v in values:
            points.append(
                ExperimentCfg.model_validate(
                    apply_sweep_value({k: x for k, x in data.items() if k != "sweep"}, path, v)
                )
            )
    for p in points:
        if p.terrain.preset is not None:
            registry.check_preset(p.terrain.preset, "terrain.preset")
        study = p.study
        if isinstance(study, SamplingStudyCfg):
            _check_names(study, "strategies", registry.check_strategy, study.strategy_options)
            _check_names(study, "metrics", registry.check_metric)
        if isinstance(study, ScannerStudyCfg):
            _check_names(study, "planners", registry.check_scan_planner)
            _check_names(study, "modes", registry.check_scan_mode)
            _check_names(study, "metrics", registry.check_metric)
        if isinstance(study, LidarStudyCfg):
            _check_names(study, "planners", registry.check_strategy, study.planner_opts)
            _check_names(study, "metrics", registry.check_metric)
            try:
                check_lidar_study(study)
            except ValueError as exc:
                raise ConfigError(str(exc)) from None


def _check_names(study, key: str, check, *args) -> None:
    """``check(name, "study.<key>[i]", *args)`` for every name of the study's list ``key``."""
    for i, name in enumerate(getattr(study, key)):
        check(name, f"study.{key}[{i}]", *args)


def resolve_terrain_files(cfg, base_dir: Path | None):
    """Resolve ``terrain.file`` / ``terrain.albedo_file`` relative to ``base_dir`` (the YAML's
    folder) and check they exist; works on any config model with a ``terrain`` section."""
    t = cfg.terrain
    updates = {}
    for key in ("file", "albedo_file"):
        p = getattr(t, key)
        if p is None:
            continue
        full = (base_dir / p) if (base_dir is not None and not p.is_absolute()) else p
        if not full.is_file():
            raise ConfigError(f"terrain.{key}: file not found: {full}{did_you_mean_file(full)}")
        updates[key] = full.resolve()
    if updates:
        cfg = cfg.model_copy(update={"terrain": t.model_copy(update=updates)})
    return cfg


def load_experiment(path: str | Path, overrides: dict[str, Any] | None = None) -> ExperimentCfg:
    """Read, override (dotted keys) and validate an experiment YAML.

    Raises
    ------
    FileNotFoundError
        The YAML (or a file it names) does not exist.
    ConfigError
        ``<file>: <key.path>: <problem>`` on one line.
    """
    path = Path(path)
    data = load_yaml(path)
    for key, value in (overrides or {}).items():
        if not isinstance(data, dict):
            break
        if key.split(".")[0] != "sweep":
            try:
                check_key_path(key, data)
            except ConfigError as exc:
                # the mistake is on the command line, not in the file
                raise ConfigError("--set " + str(exc).removeprefix("sweep.")) from None
        data = apply_sweep_value(data, key, value)
    try:
        return validate_data(data, base_dir=path.parent)
    except ConfigError as exc:
        key = _override_at(str(exc), overrides or {})
        if key is None:
            raise ConfigError(f"{path}: {exc}") from None
        where, _, problem = str(exc).partition(": ")
        # a value given by --set is reported as the --set's, not as a line of the file
        raise ConfigError(
            f"--set {key}: {problem}" if where == key else f"--set {key}: {exc}"
        ) from None


def _override_at(message: str, overrides: dict[str, Any]) -> str | None:
    """The ``--set`` key whose value a ``<key.path>: <problem>`` message is about (the key
    itself or a key inside it), or None when the problem is in the file."""
    where = message.partition(": ")[0]
    for key in sorted(overrides, key=len, reverse=True):
        if where == key or where.startswith((f"{key}.", f"{key}[")):
            return key
    return None


def to_plain(cfg: ExperimentCfg) -> dict:
    """JSON/YAML-safe dict of a config (paths as strings, aliases used)."""
    return cfg.model_dump(mode="json", by_alias=True)
