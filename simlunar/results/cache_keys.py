"""Cache keys that survive new options: a key added to the schema at the value that changes
no number is left out of a unit's cache key, so results computed before it existed stay valid.

:func:`simlunar.pipeline.runner.unit_key` applies :func:`without_new_defaults` to the study
section, and so does a result folder's identity (:func:`simlunar.results.folder.claim_folder`:
a folder written before a key existed takes a rerun of the same experiment); the tables below
must equal the schema's defaults (a test keeps them so).
"""

from __future__ import annotations

from simlunar.study.reconstruction_spec import parse_reconstructions

__all__ = [
    "EXPORT_ONLY_KEYS",
    "NEW_BSDF_DEFAULTS",
    "NEW_NESTED_DEFAULTS",
    "NEW_PLANNER_DEFAULTS",
    "NEW_RENDER_DEFAULTS",
    "NEW_STUDY_DEFAULTS",
    "NEW_TERRAIN_DEFAULTS",
    "reconstruction_versions",
    "render_without_new_defaults",
    "terrain_without_new_defaults",
    "without_new_defaults",
]

#: study keys added after caches existed, with the value that gives the numbers of before
NEW_STUDY_DEFAULTS = {"score_region": "full", "reconstructions": ["linear"]}
#: study keys that ask for files besides the results and change no number at any value: never
#: in a cache key or a folder's identity (``--save-arrays`` on a finished folder computes its
#: units again for the export only; results.csv stays byte-identical)
EXPORT_ONLY_KEYS = ("save_arrays",)
#: planner option keys added after caches existed (placement, oracles, sequential), with defaults
NEW_PLANNER_DEFAULTS = {
    "placement": "random",
    "density_power": None,
    "lloyd_iterations": 20,
    "border_pitch": 0.75,
    "oracle": {"start_share": 0.25, "batch_share": 0.15, "smooth_pitch": 0.25, "nms_pitch": 1.0},
    "sequential": {"max_rounds": 12, "first_share": 0.3, "batch_share": 0.12, "temper": 0.5,
                   "uniform_mix": 0.5, "prior_power": 0.5, "nms_pitches": 0.7, "prior": "none"},
}  # fmt: skip
#: render keys added after caches existed, with the value that gives the numbers of before
NEW_RENDER_DEFAULTS = {"guide_frames": []}
#: BSDF block keys added after caches existed (per ``kind``), with the value that gives the
#: numbers of before (Hapke's coherent backscatter: unset = none)
NEW_BSDF_DEFAULTS = {"hapke": {"B_C0": None, "h_C": None}}
#: keys added inside a planner option section after the table above, with their defaults
#: (a LIDAR planner's ``fit``: the absolute budgets)
NEW_NESTED_DEFAULTS = {
    "sequential": {"first_round": "uniform"},
    "oracle": {"reconstruction": "linear"},
    "fit": {"budget_s": None, "budget_j": None},
}
#: terrain keys added after caches existed, with the value that gives the terrain of before
#: (a DEM file as read: not refined, no rocks stamped on it)
NEW_TERRAIN_DEFAULTS = {"refine_m": None, "rocks": None}


def without_new_defaults(study: dict) -> dict:
    """The study section less keys added later at the value that changes nothing, so the
    cache keys of earlier runs stay valid, and less the export-only keys
    (:data:`EXPORT_ONLY_KEYS`) (tests/pipeline/test_runner.py keeps the tables
    equal to the schema's defaults)."""
    out = {
        k: v
        for k, v in study.items()
        if NEW_STUDY_DEFAULTS.get(k, object()) != v and k not in EXPORT_ONLY_KEYS
    }

    def strip(opts):
        if not isinstance(opts, dict):
            return opts
        fo = opts.get("feature_opts")
        if isinstance(fo, dict) and fo.get("model", 0) is None:
            opts = {**opts, "feature_opts": {k: v for k, v in fo.items() if k != "model"}}
        for section, news in NEW_NESTED_DEFAULTS.items():
            sub = opts.get(section)
            if isinstance(sub, dict):
                sub = {k: v for k, v in sub.items() if news.get(k, object()) != v}
                opts = {**opts, section: sub}
        return {k: v for k, v in opts.items() if NEW_PLANNER_DEFAULTS.get(k, object()) != v}

    if isinstance(out.get("strategy_options"), dict):
        out["strategy_options"] = {k: strip(v) for k, v in out["strategy_options"].items()}
    if isinstance(out.get("planner_opts"), dict):  # the lidar study's planners
        out["planner_opts"] = {k: strip(v) for k, v in out["planner_opts"].items()}
    options = out.get("options")
    if isinstance(options, dict) and isinstance(options.get("planner_opts"), dict):
        planner_opts = {k: strip(v) for k, v in options["planner_opts"].items()}
        out["options"] = {**options, "planner_opts": planner_opts}
    return out


def terrain_without_new_defaults(terrain: dict) -> dict:
    """The terrain section less keys added later at the value that changes nothing
    (:data:`NEW_TERRAIN_DEFAULTS`), so the cache keys of earlier runs stay valid."""
    return {k: v for k, v in terrain.items() if NEW_TERRAIN_DEFAULTS.get(k, object()) != v}


def render_without_new_defaults(render: dict) -> dict:
    """The render section less keys added later at the value that changes nothing (no extra
    guide frames; in the BSDF block, :data:`NEW_BSDF_DEFAULTS`), so the cache keys of earlier
    runs stay valid."""
    out = {k: v for k, v in render.items() if NEW_RENDER_DEFAULTS.get(k, object()) != v}
    bsdf = out.get("bsdf")
    news = NEW_BSDF_DEFAULTS.get(bsdf.get("kind")) if isinstance(bsdf, dict) else None
    if news:
        out["bsdf"] = {k: v for k, v in bsdf.items() if news.get(k, object()) != v}
    return out


def reconstruction_versions(study: dict) -> dict:
    """``{registered name: version}`` of the configured reconstructions whose registry entry
    states a ``results_version`` (bumped when a change of the method changes its numbers under
    the same options, e.g. the learned reconstruction's held-out check): part of a unit's
    cache key, so cached results of the method as it was are not served; empty (the key as
    before) when no configured reconstruction states one."""
    # imported here: results.folder imports this module, and the reconstructions (their
    # scientific stack) are needed only to key a unit, not to read a folder
    from simlunar.reconstruction import RECONSTRUCTIONS

    out = {}
    for spec in parse_reconstructions(study.get("reconstructions")):
        entry = RECONSTRUCTIONS[spec.name] if spec.name in RECONSTRUCTIONS else None
        version = None if entry is None else entry.meta.get("results_version")
        if version is not None:
            out[spec.name] = version
    return out
