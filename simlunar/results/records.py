"""Work units: what one sweep point is (:class:`WorkUnit`, its label) and what it returns (its
typed record and the dict form executors carry and the unit cache stores)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from simlunar.results.store import fmt_value

__all__ = ["UnitRecord", "WorkUnit", "unit_label"]


@dataclass(frozen=True, eq=False)
class UnitRecord:
    """What one work unit returns (its dict form, :meth:`to_dict`, is what executors carry
    and the unit cache stores).

    Attributes
    ----------
    rows : list of dict
        Tidy result rows (sampling: strategy, density, k, trial, metric, value).
    scores : dict
        ``{metric: {strategy: score}}`` (eq. 4.3); empty for scanner units.
    arrays : dict of str -> ndarray
        Figure arrays (image, depth, wavelet energy, plan, reconstruction, ...).
    timings : dict of str -> float
        Stage -> seconds.
    meta : dict
        Image shape, spacing, Mitsuba variant, filled ground-truth pixels.
    scans : dict or None
        Scanner units with ``study.save_scans``: the scan export payload
        (:func:`simlunar.results.exports.scan_export_payload`), which the runner writes to
        ``scans/unit<i>/`` and drops before caching; None otherwise (then absent from the dict
        form, so cached results are unchanged).
    exports : dict or None
        Units with ``study.save_arrays``: the reconstructions to export
        (:func:`simlunar.results.array_exports.array_export_payload`), written by the runner
        to ``arrays/unit<i>/`` and dropped before caching; None otherwise (absent from the
        dict form).
    """

    rows: list[dict[str, Any]]
    scores: dict[str, dict[str, float]]
    arrays: dict[str, np.ndarray]
    timings: dict[str, float]
    meta: dict[str, Any] = field(default_factory=dict)
    scans: dict[str, Any] | None = None
    exports: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        out = {
            "rows": self.rows,
            "scores": self.scores,
            "arrays": self.arrays,
            "timings": self.timings,
            "meta": self.meta,
        }
        if self.scans is not None:
            out["scans"] = self.scans
        if self.exports is not None:
            out["exports"] = self.exports
        return out


@dataclass(frozen=True)
class WorkUnit:
    """One sweep point.

    Attributes
    ----------
    index : int
        Position in the sweep's cartesian product (results order).
    key : str
        SHA-256 (hex, 16 chars) of the resolved configuration: the cache key.
    sweep : dict
        Dotted key path -> value of this point (empty without a sweep).
    config : dict
        The full resolved configuration (plain, JSON-safe) without ``sweep``.
    inputs : dict
        Key path -> ``{"path", "sha256"}`` of every file the unit reads.
    terrain_seed : int or None
        The unit's terrain realisation (``terrain.seed_index``) when the experiment repeats
        over ``study.terrain_seeds`` > 1; None otherwise.
    """

    index: int
    key: str
    sweep: dict[str, Any]
    config: dict[str, Any]
    inputs: dict[str, dict[str, str]] = field(default_factory=dict)
    terrain_seed: int | None = None


def unit_label(u: WorkUnit) -> str:
    """Short human label of a sweep point (``elevation_deg=30``)."""
    seed = [] if u.terrain_seed is None else [f"terrain_seed={u.terrain_seed}"]
    if not u.sweep:
        return ", ".join(seed) or u.config.get("name", f"unit {u.index}")
    parts = []
    for path, v in u.sweep.items():
        name = path.rsplit(".", 1)[-1]
        if isinstance(v, dict) and "kind" in v:  # e.g. rover_mast(depression_deg=30)
            rest = ", ".join(f"{k}={fmt_value(x)}" for k, x in v.items() if k != "kind")
            v = f"{v['kind']}({rest})" if rest else v["kind"]
        elif isinstance(v, dict):
            v = json.dumps(v, sort_keys=True)
        elif v is None:
            v = "default"
        parts.append(f"{name}={fmt_value(v)}")
    return ", ".join(parts + seed)
