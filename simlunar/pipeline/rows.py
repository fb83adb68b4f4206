"""The tidy rows of a run's ``results.csv``: every unit's cached rows in a fixed order (units in
sweep order; rows by strategy, reconstruction, density, trial and metric in config order) and
the CSV columns, so the same seed gives the same file whatever the completion order."""

from __future__ import annotations

from simlunar.results.records import WorkUnit
from simlunar.study.protocol import exposure_count
from simlunar.study.reconstruction_spec import parse_reconstructions

__all__ = ["DEFAULT_RECONSTRUCTION", "ROW_COLUMNS", "collect_rows"]

#: the row columns in their fixed order (each present when some row has it); ``reconstruction``
#: is in every row (``linear`` for rows cached before reconstructions were configurable)
ROW_COLUMNS = (
    "mode", "planner", "budget", "strategy", "reconstruction", "guide_frames", "exposures",
    "density", "k", "trial", "metric", "value",
)  # fmt: skip
#: the reconstruction of every row written before rows named theirs
DEFAULT_RECONSTRUCTION = "linear"


def _sort_rows(rows: list[dict], config: dict) -> list[dict]:
    study = config.get("study", {})
    strategies = list(study.get("strategies") or [])
    metrics = list(study.get("metrics") or [])
    recons = [spec.label for spec in parse_reconstructions(study.get("reconstructions"))]

    def order(seq, v):
        return seq.index(v) if v in seq else len(seq)

    def key(r):
        return (
            order(strategies, r.get("strategy")),
            str(r.get("strategy", "")),
            order(recons, r.get("reconstruction")),
            str(r.get("reconstruction", "")),
            -float(r.get("density", 0.0) or 0.0),
            int(r.get("trial", 0) or 0),
            order(metrics, r.get("metric")),
            str(r.get("metric", "")),
        )

    return sorted(rows, key=key)


def collect_rows(units: list[WorkUnit], records: dict[str, dict]) -> tuple[list[dict], list[str]]:
    """All tidy rows in the fixed results order, and the CSV columns."""
    sweep_cols = list(units[0].sweep) if units else []
    if any(u.terrain_seed is not None for u in units):
        sweep_cols.append("terrain_seed")
    extra: list[str] = []
    rows: list[dict] = []
    for u in units:
        point = {**u.sweep, "terrain_seed": u.terrain_seed}
        cached = records[u.key]["rows"]
        cached = [{"reconstruction": DEFAULT_RECONSTRUCTION, **r} for r in cached]
        # the exposures a row's frames cost, from the frames it names (records cached before
        # a derived frame stopped counting as an exposure of its own say so too)
        cached = [
            {**r, "exposures": exposure_count(r["guide_frames"])}
            if isinstance(r.get("guide_frames"), str) and r.get("exposures") not in (None, "")
            else r
            for r in cached
        ]
        for r in _sort_rows(cached, u.config):
            for c in r:
                if c not in ROW_COLUMNS and c not in extra:
                    extra.append(c)
            rows.append({"unit": u.index, **{c: point[c] for c in sweep_cols}, **r})
    present = {c for r in rows for c in r}
    known = [c for c in ROW_COLUMNS if c != "value" and c in present]
    # the study's own columns by name: a cached record's rows come back from JSON with their
    # keys sorted, a fresh one's in the order the study made them, so a resumed run would
    # otherwise write another column order than a clean one
    return rows, ["unit", *sweep_cols, *known, *sorted(extra), "value"]
