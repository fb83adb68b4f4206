"""Warnings about valid but probably unintended settings (the run goes on).

A sun below :data:`LOW_SUN_DEG` above the horizon is allowed (the schema takes any elevation
in (0, 90] deg) but lights the terrain at grazing incidence: nearly every cell is in cast
shadow, so the guide image is mostly black and the study says little. The lunar polar sites
do see such suns, so this is a warning, not an error.
"""

from __future__ import annotations

from typing import Any

from simlunar.config.loading import apply_sweep_value, to_plain
from simlunar.config.schema import ExperimentCfg

__all__ = ["LOW_SUN_DEG", "config_warnings"]

#: a sun below this elevation (deg) gets a warning
LOW_SUN_DEG = 1.0


def _sun_warning(light: Any, where: str) -> str | None:
    if getattr(light, "kind", None) != "sun" or light.elevation_deg >= LOW_SUN_DEG:
        return None
    return (
        f"warning: {where}: the sun at {light.elevation_deg:g} deg is below {LOW_SUN_DEG:g} "
        "deg: at grazing incidence nearly every cell is in cast shadow and the guide image "
        "is mostly black (the paper's scenes: 5-90 deg); the run goes on"
    )


def config_warnings(cfg: ExperimentCfg) -> list[str]:
    """One line per probably-unintended setting of an experiment and of each sweep value.

    Lines start with ``warning:`` and name the key (``render.light.elevation_deg`` or
    ``sweep.render.light.elevation_deg[2]``).
    """
    lines = []
    if not any(p.startswith("render.light") for p in cfg.sweep):
        line = _sun_warning(cfg.render.light, "render.light.elevation_deg")
        if line:
            lines.append(line)
    plain = {k: v for k, v in to_plain(cfg).items() if k != "sweep"}
    for path, values in cfg.sweep.items():
        if not path.startswith("render.light"):
            continue
        for i, v in enumerate(values):
            point = ExperimentCfg.model_validate(apply_sweep_value(plain, path, v))
            line = _sun_warning(point.render.light, f"sweep.{path}[{i}]")
            if line:
                lines.append(line)
    return lines
