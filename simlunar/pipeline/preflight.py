"""Checks that run before any render or write: input files, geometry, sizes, the result folder.

The schema (:mod:`simlunar.config.schema`) checks each value on its own; what needs a file
or the geometry of a sweep point is checked here, for every sweep point, before the first
unit starts, so a mistake costs a second instead of the units computed before it:

- the DEM and albedo files a unit reads: readable, 2-D, at least 2 x 2 cells, numeric, finite
  heights within :data:`MAX_ABS_COORD_M`, a scalar spacing, albedo of the DEM's shape in
  [0, 1], and at most :data:`MAX_NAN_FRACTION` of NaN heights (holes);
- the camera: a perspective camera must have a view direction and see the terrain;
- the sizes: every density must give at least 3 samples on the unit's image, a scanner's
  projector and camera sizes must be positive;
- the output folder: not a file, not below a file, writable, ``units/`` and ``figures/``
  folders where present.

Every problem is a :class:`~simlunar.errors.ConfigError` (or
:class:`~simlunar.errors.ResultFolderError`) whose one-line message names the key path or
the file. The same module hashes the files a unit reads (:func:`input_hashes`): they are part
of the unit's cache key, so a changed DEM is recomputed.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from simlunar.config.scanner_translate import coding_options, rig_kwargs
from simlunar.config.schema import ExperimentCfg
from simlunar.errors import ConfigError, InfrastructureError
from simlunar.metrics.interior import interior_mask, sparsest_pitch
from simlunar.pipeline.inputs import (
    MAX_ABS_COORD_M,
    MAX_NAN_FRACTION,
    TerrainFacts,
    check_size,
    model_inputs,
    terrain_facts,
)
from simlunar.pipeline.out_paths import check_out_dir, check_out_file
from simlunar.pipeline.preflight_lidar import check_lidar, grid_rays, perspective_camera
from simlunar.pipeline.unit_models import read_unit_models
from simlunar.planner import check_k
from simlunar.render.backend import choose_variant
from simlunar.results.records import unit_label
from simlunar.scanner.codings import CODINGS, coding_for
from simlunar.scanner.rescan import SCAN_PLANNERS
from simlunar.sensors.structured_light import DOT_MODES, mode_coding
from simlunar.study.scanner import aim_rig_at_terrain

__all__ = [
    "DOT_MODES",
    "MAX_NAN_FRACTION",
    "MIN_SAMPLES",
    "Preflight",
    "check_camera",
    "check_out_dir",
    "check_out_file",
    "check_renderer",
    "check_rig",
    "check_scanner_budget",
    "check_study_sizes",
    "check_units",
    "image_shape",
    "terrain_facts",
]

#: smallest sample count of a density (the planners and the Delaunay reconstruction need 3)
MIN_SAMPLES = 3


# --------------------------------------------------------------------------- renderer
def check_renderer() -> None:
    """``SIMLUNAR_VARIANT``, when set, must name a Mitsuba variant this machine can run
    (a known name; ``cuda_ad_rgb`` needs a usable GPU, ``llvm_ad_rgb`` a libLLVM): the
    backend's own choice, made without importing Mitsuba, before anything is written."""
    wanted = os.environ.get("SIMLUNAR_VARIANT")
    if not wanted:
        return  # the backend falls back by itself

    try:
        choose_variant()
    except ValueError as exc:  # a name that is no variant: the user's input
        raise ConfigError(f"SIMLUNAR_VARIANT={wanted}: {exc}") from None
    except RuntimeError as exc:
        # a known variant this machine cannot run (no GPU, no libLLVM): the environment
        # failed, not the input (exit 3)
        raise InfrastructureError(f"SIMLUNAR_VARIANT={wanted}: {exc}") from None


# --------------------------------------------------------------------------- input hashes


# --------------------------------------------------------------------------- camera
def image_shape(render: Any, facts: TerrainFacts) -> tuple[int, int]:
    """(rows, cols) of a unit's rendered image."""
    cam = render.camera
    if getattr(cam, "kind", None) != "orthographic_nadir" and hasattr(cam, "width"):
        return (int(cam.height), int(cam.width))
    return (facts.rows, facts.cols)


def check_camera(render: Any, facts: TerrainFacts, *, key: str = "render.camera") -> None:
    """A perspective camera must have a view direction and see part of the terrain.

    ``render`` is a ``RenderCfg`` (an experiment's or a scene's).

    Rays through a grid of pixels (the corners included) are intersected with the terrain's
    bounding box; if none meets it, no pixel can see the terrain. The image's pixel count is
    within :data:`MAX_CELLS`.
    """
    rows, cols = image_shape(render, facts)
    check_size(key, f"a {rows} x {cols} image", rows * cols)
    cam = render.camera
    if getattr(cam, "kind", None) == "rover_mast":
        _check_site(cam, facts, key)
        return
    if getattr(cam, "kind", None) != "perspective":
        return

    pos = np.asarray(cam.position_m, float)
    target = np.asarray(cam.look_at_m, float)
    for name, v in (("position_m", pos), ("look_at_m", target)):
        if not np.all(np.isfinite(v)) or np.abs(v).max() > MAX_ABS_COORD_M:
            raise ConfigError(
                f"{key}.{name}: coordinates must be finite and within "
                f"{MAX_ABS_COORD_M:.0e} m, got {v.tolist()}"
            )
    if np.linalg.norm(target - pos) < 1e-9 * max(1.0, np.abs(pos).max()):
        raise ConfigError(
            f"{key}.look_at_m: equals position_m {pos.tolist()}; the camera has no view direction"
        )
    camera = perspective_camera(cam, key)
    o, d = grid_rays(camera)
    x0, x1, y0, y1 = facts.extent
    lo = np.array([x0, y0, facts.zmin])
    hi = np.array([x1, y1, facts.zmax])
    if not np.any(_ray_box(o, d, lo, hi)):
        raise ConfigError(
            f"{key}: the camera at {pos.tolist()} looking at {target.tolist()} sees no "
            f"terrain (the terrain spans x [{x0:g}, {x1:g}] m, y [{y0:g}, {y1:g}] m, "
            f"z [{facts.zmin:.3g}, {facts.zmax:.3g}] m)"
        )


def _check_site(cam: Any, facts: TerrainFacts, key: str) -> None:
    """A rover mast stands on the terrain: its site must lie within the cell centres."""
    site = getattr(cam, "site_m", None)
    if site is None:
        return  # the terrain's centre
    x0, x1, y0, y1 = facts.extent
    h = 0.5 * facts.spacing
    x, y = float(site[0]), float(site[1])
    if not (x0 + h <= x <= x1 - h and y0 + h <= y <= y1 - h):
        raise ConfigError(
            f"{key}.site_m: [{x:g}, {y:g}] m lies outside the terrain (cell centres span "
            f"x [{x0 + h:g}, {x1 - h:g}] m, y [{y0 + h:g}, {y1 - h:g}] m)"
        )


def _ray_box(o: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Whether each ray ``o + t d`` (t >= 0) meets the box [lo, hi] (slab method)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t1 = (lo - o) * inv
        t2 = (hi - o) * inv
    tmin = np.where(np.isnan(t1), -np.inf, np.minimum(t1, t2))
    tmax = np.where(np.isnan(t2), np.inf, np.maximum(t1, t2))
    # a ray parallel to a slab (d = 0) misses unless its origin lies inside the slab
    par = d == 0
    inside = (o >= lo) & (o <= hi)
    tmin = np.where(par, np.where(inside, -np.inf, np.inf), tmin)
    tmax = np.where(par, np.where(inside, np.inf, -np.inf), tmax)
    near = tmin.max(axis=-1)
    far = tmax.min(axis=-1)
    return (far >= np.maximum(near, 0.0)) & np.isfinite(far)


# --------------------------------------------------------------------------- sizes
def check_study_sizes(cfg: Any, shape: tuple[int, int]) -> None:
    """Densities give at least :data:`MIN_SAMPLES` samples; the image is within
    :data:`MAX_CELLS`; scanner sizes are positive and within the limits."""
    s = cfg.study
    n = shape[0] * shape[1]
    kind = getattr(s, "kind", "sampling")
    if kind in ("sampling", "lidar"):  # a lidar study plans k = density x guide pixels too
        for i, d in enumerate(s.densities):
            k = round(d * n)
            if k < MIN_SAMPLES:
                raise ConfigError(
                    f"study.densities[{i}]: density {d:g} gives {k} samples on the "
                    f"{shape[0]} x {shape[1]} image (at least {MIN_SAMPLES} needed: "
                    f"density >= {MIN_SAMPLES / n:.3g})"
                )
        return
    for name in ("projector_px", "camera_px"):
        size = getattr(s, name, None)
        if size is None:
            continue
        if len(size) != 2 or any(int(v) < 2 for v in size):
            raise ConfigError(
                f"study.{name}: (width, height) must be at least 2 pixels each, got {list(size)}"
            )
    check_scanner_budget(s)


def check_scanner_budget(s: Any) -> None:
    """A scanner study's sizes against :data:`MAX_CELLS` / :data:`MAX_FRAME_PIXELS`, and its
    dot budget against the grid the dots are planned on (the projector's: guide pixel (r, c)
    is projector pixel (r, c)), with the planners' own sample-count rule."""

    (pw, ph), (cw, ch) = s.projector_px, s.camera_px
    check_size("study.projector_px", f"{pw} x {ph} pixels", pw * ph)
    check_size("study.camera_px", f"{cw} x {ch} pixels", cw * ch)
    per_frame = pw * ph + cw * ch
    # the largest captured stack (+ kept frames) of the full-field codings the modes scan with
    codings = coding_options(s.options)
    scanned = dict.fromkeys(mode_coding(m, s.coding) for m in s.modes)
    for name in [n for n in scanned if n is not None]:
        try:  # a coding's rules on the projector's size (a phase that repeats within it)
            n = coding_for(codings, name).frames((ph, pw))
        except ValueError as exc:
            raise ConfigError(f"study.options.{CODINGS[name].meta['yaml_key']}: {exc}") from None
        check_size(
            "study.projector_px",
            f"{n} {name.replace('_', '-')} frames x {per_frame} projector + camera pixels",
            n * per_frame,
            "SIMLUNAR_MAX_FRAME_PIXELS",
        )
    if not set(DOT_MODES) & set(s.modes):
        return
    batch = s.options.dot_opts.batch
    check_size(
        "study.options.dot_opts.batch",
        f"{batch} frames x {per_frame} projector + camera pixels",
        batch * per_frame,
        "SIMLUNAR_MAX_FRAME_PIXELS",
    )
    n = pw * ph
    k = max(1, round(s.budget * n))  # the structured-light sensor: dots planned on the projector
    for planner in s.planners:
        if planner in SCAN_PLANNERS:
            continue
        try:
            check_k(k, n)
        except ValueError as exc:
            raise ConfigError(
                f"study.budget: {s.budget:g} of the {pw} x {ph} projector gives {k} dots for "
                f"planner {planner} ({exc})"
            ) from None


# --------------------------------------------------------------------------- scanner rig
def check_rig(cfg: Any, facts: TerrainFacts, *, key: str = "study.options.rig") -> None:
    """A scanner study's rig, built as the unit builds it (the library's preset and aiming,
    so its own checks apply: a zero baseline, ...), must see the terrain: rays of the
    projector's frustum must meet the terrain's bounding box, and the triangulation camera
    must see where they meet. A cheap ray cast instead of a render that finds nothing."""
    from types import SimpleNamespace

    stand_in = SimpleNamespace(extent=facts.extent, heights=np.array([facts.zmid]))
    try:
        rig = aim_rig_at_terrain(stand_in, **rig_kwargs(cfg.study))
    except ValueError as exc:
        raise ConfigError(f"{key}: {exc}") from None
    x0, x1, y0, y1 = facts.extent
    lo, hi = np.array([x0, y0, facts.zmin]), np.array([x1, y1, facts.zmax])
    pw, ph = cfg.study.projector_px
    uu, vv = np.meshgrid(np.linspace(0.5, pw - 0.5, 17), np.linspace(0.5, ph - 0.5, 13))
    o, d = rig.projector.rays(np.stack([uu, vv], axis=-1).reshape(-1, 2))
    hit = _ray_box(o, d, lo, hi)
    if not hit.any():
        raise ConfigError(
            f"{key}: the projector at {np.round(rig.projector.position, 3).tolist()} sees no "
            f"terrain (x [{x0:g}, {x1:g}] m, y [{y0:g}, {y1:g}] m)"
        )
    # where the projector's rays reach the terrain's median height: what the camera must see
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (facts.zmid - o[hit, 2]) / d[hit, 2]
    pts = o[hit] + np.where(np.isfinite(t) & (t > 0), t, np.nan)[:, None] * d[hit]
    pts = pts[np.isfinite(pts).all(axis=1)]
    uv, z = rig.camera.project(pts) if len(pts) else (np.zeros((0, 2)), np.zeros(0))
    cw, ch = cfg.study.camera_px
    seen = (z > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < cw) & (uv[:, 1] >= 0) & (uv[:, 1] < ch)
    if not seen.any():
        raise ConfigError(
            f"{key}: the camera at {np.round(rig.camera.position, 3).tolist()} does not see "
            "the projected pattern on the terrain (check baseline_m, cam_fov_x_deg, verge)"
        )
    _check_rig_geometry(rig, facts, key)


#: least height of a scanner's projector above the terrain's median height, in terrain cells:
#: closer, it sits inside the relief of the bed it is meant to scan
MIN_PROJECTOR_CELLS = 10
#: most camera-projector baseline, in projector standoffs: beyond it the camera sees the
#: pattern at a grazing angle (a verged camera more than ~80 deg off the projector's axis)
MAX_BASELINE_STANDOFFS = 5.0


def _check_rig_geometry(rig: Any, facts: TerrainFacts, key: str) -> None:
    """A projector above the terrain's relief and a baseline a triangulation can use."""
    x0, x1, y0, y1 = facts.extent
    target = np.array([(x0 + x1) / 2, (y0 + y1) / 2, facts.zmid])
    proj = np.asarray(rig.projector.position, float)
    least = MIN_PROJECTOR_CELLS * facts.spacing
    height = float(proj[2] - facts.zmid)
    if not height >= least:
        raise ConfigError(
            f"{key}: the projector is {height:.3g} m above the terrain's median height, inside "
            f"its relief (at least {MIN_PROJECTOR_CELLS} cells = {least:g} m; raise "
            "distance_m / altitude_m or fill)"
        )
    standoff = float(np.linalg.norm(proj - target))
    baseline = float(np.linalg.norm(np.asarray(rig.camera.position, float) - proj))
    if baseline > MAX_BASELINE_STANDOFFS * standoff:
        raise ConfigError(
            f"{key}: a baseline of {baseline:.3g} m is more than {MAX_BASELINE_STANDOFFS:g} x "
            f"the projector's {standoff:.3g} m standoff: the camera would see the pattern at a "
            "grazing angle (lower baseline_m)"
        )


# --------------------------------------------------------------------------- all units
@dataclass(frozen=True)
class Preflight:
    """What the checks found: per unit its terrain facts (holes reported in provenance)."""

    terrain: tuple[TerrainFacts, ...]

    def holes(self) -> list[dict[str, Any]]:
        """Terrain files with NaN holes: file, share and how they are filled (deduplicated)."""
        seen: dict[str, dict[str, Any]] = {}
        for f in self.terrain:
            if f.nan_fraction > 0 and f.source not in seen:
                seen[f.source] = {
                    "file": f.source,
                    "nan_fraction": f.nan_fraction,
                    "filled": "ground-truth pixels without a hit take the depth of the "
                    "nearest valid pixel",
                    "max_nan_fraction": MAX_NAN_FRACTION,
                }
        return list(seen.values())


def check_score_region(cfg: Any, shape: tuple[int, int]) -> None:
    """A sampling study scored on the interior must have one: the border band of the
    sparsest density's pitch (:func:`simlunar.metrics.interior_mask`) leaves some cell."""
    s = cfg.study
    if getattr(s, "kind", None) != "sampling" or getattr(s, "score_region", "full") == "full":
        return

    try:
        interior_mask(shape, sparsest_pitch(shape, s.densities))
    except ValueError as exc:
        raise ConfigError(
            f"study.score_region: {s.score_region}: {exc} (a {shape[0]} x {shape[1]} image at "
            f"density {min(s.densities):g}; use score_region: full, a larger image or denser "
            "sampling)"
        ) from None


def check_models(
    inputs: dict[str, dict[str, str]], config: dict[str, Any], seen: set | None = None
) -> None:
    """Load every trained model a unit names (every option declared a ``model`` file: the
    learned map's, the learned reconstruction's), as the unit will (its record checked and its
    bytes' hash compared with the record's before unpickling), so an absent, truncated,
    foreign, renamed or mismatched model file is one line naming it before any render or
    write.

    ``inputs``: the unit's :func:`~simlunar.pipeline.inputs.input_hashes`; ``config``: its
    plain config; ``seen``: the (key, path, hash) triples already loaded (a sweep loads each
    model once).
    """
    seen = set() if seen is None else seen
    for key in model_inputs(config):
        v = inputs.get(key)
        if v is None:
            continue
        rec = inputs.get(f"{key}.json", {})
        memo = (key, v["path"], v["sha256"], rec.get("sha256"))
        if memo in seen:
            continue
        read_unit_models({key: v, **({f"{key}.json": rec} if rec else {})}, config)
        seen.add(memo)


def check_units(units: list[Any]) -> Preflight:
    """Check every unit (sweep point) before any of them runs.

    ``units`` are :class:`~simlunar.results.records.WorkUnit` (their plain ``config``).
    Errors of a sweep point name the point: ``sweep point 3 (elevation_deg=0): ...``.
    """

    facts = []
    checked_models: set[tuple] = set()
    for u in units:
        cfg = ExperimentCfg.model_validate(u.config)
        try:
            check_models(getattr(u, "inputs", None) or {}, u.config, checked_models)
            f = terrain_facts(cfg.terrain)
            check_camera(cfg.render, f)
            check_study_sizes(cfg, image_shape(cfg.render, f))
            check_score_region(cfg, image_shape(cfg.render, f))
            if getattr(cfg.study, "kind", None) == "lidar":
                check_lidar(cfg, f)
            if getattr(cfg.study, "kind", None) == "scanner":
                check_rig(cfg, f)
        except ConfigError as exc:
            if len(units) > 1 and u.sweep:
                raise ConfigError(f"sweep point {u.index} ({unit_label(u)}): {exc}") from None
            raise
        facts.append(f)
    return Preflight(tuple(facts))
