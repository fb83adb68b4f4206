"""Setting up a structured-light scanner study: the rig aimed at the terrain, the projector's
depth range over it, and the planner of the guide pixels to rescan (split from
:mod:`simlunar.study.scanner`, which re-exports these names)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from simlunar.features import check_image
from simlunar.geometry import Rig
from simlunar.planner import plan, strategy_weights
from simlunar.render.capture import GuideView
from simlunar.scanner.rescan import SCAN_PLANNERS, low_contrast_pixels
from simlunar.scanner.rigs import RIG_PRESETS, rig_preset
from simlunar.sensors.structured_light import StructuredLight

__all__ = ["aim_rig_at_terrain", "depth_range_from_terrain", "guided_weights"]


def depth_range_from_terrain(terrain, rig: Rig, *, margin: float = 0.05) -> tuple[float, float]:
    """Projector z-depth range of the terrain's cell centres inside the projector's view (m)."""
    pts = terrain.points().reshape(-1, 3)
    pts = pts[np.isfinite(pts).all(axis=1)]
    uv, z = rig.projector.project(pts)
    H, W = rig.projector.intrinsics.shape
    inside = (z > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < W) & (uv[:, 1] >= 0) & (uv[:, 1] < H)
    if not inside.any():
        raise ValueError("the projector does not see the terrain")
    z = z[inside]
    return (float(z.min() * (1 - margin)), float(z.max() * (1 + margin)))


def guided_weights(name: str, image: np.ndarray, opts: Mapping) -> tuple[np.ndarray, dict]:
    """The weights of strategy ``name`` on the guide ``image`` (with the ``feature_opts`` and
    ``coefficients`` of its options ``opts``) and the rest of ``opts``: the keywords of its
    :func:`~simlunar.planner.plan`."""
    rest = dict(opts)
    feature_opts = rest.pop("feature_opts", None)
    coefficients = rest.pop("coefficients", None)
    return strategy_weights(name, image, feature_opts=feature_opts, coefficients=coefficients), rest


def _scan_planner(name: str, o, mode: str, guide: GuideView, sensor: StructuredLight):
    """The planner of the guide pixels to rescan: from the guide image, or from the coded
    scan for a :data:`~simlunar.scanner.rescan.SCAN_PLANNERS` planner."""
    opts = o.planner_opts.get(name, {})
    if name in SCAN_PLANNERS:
        if mode != "ambiguity_enhancement":
            raise ValueError(
                f"planner {name!r} ranks the pixels of a coded scan: use it with the "
                "ambiguity_enhancement mode"
            )
        if opts:
            raise ValueError(f"planner {name!r} takes no options, got {sorted(opts)}")
        return lambda k, rng: low_contrast_pixels(sensor.coded_scan(), k, rng=rng)
    image = check_image(np.asarray(guide.image, float))
    weights, opts = guided_weights(name, image, opts)

    def planner(k, rng):
        p = plan(name, int(k), weights=weights, shape=image.shape, rng=rng, **opts)
        return np.stack([np.asarray(p.rows), np.asarray(p.cols)], axis=-1).astype(np.int64)

    return planner


def aim_rig_at_terrain(
    terrain,
    *,
    preset: str = "moonyard",
    proj_size=(128, 96),
    cam_size=(256, 192),
    fill: float = 0.9,
    **kw,
) -> Rig:
    """A preset rig aimed at the terrain's centre, at the standoff that fits the projection in it.

    The projector's horizontal footprint is ``fill`` times the smaller side of the terrain (so
    every guide pixel sees terrain). Extra keywords go to the preset (elevation, baseline, ...).
    """
    if preset not in RIG_PRESETS:
        raise ValueError(f"unknown rig preset {preset!r}; valid: {sorted(RIG_PRESETS)}")
    xmin, xmax, ymin, ymax = terrain.extent
    target = np.array([(xmin + xmax) / 2, (ymin + ymax) / 2, float(np.nanmedian(terrain.heights))])
    fov = kw.pop("fov_x", np.radians(50.0) if preset == "moonyard" else np.radians(30.0))
    side = min(xmax - xmin, (ymax - ymin) * proj_size[0] / proj_size[1])
    dist = fill * side / (2 * np.tan(fov / 2))
    if preset == "moonyard":
        kw.setdefault("distance", dist)
        kw.setdefault("baseline", 0.25 * dist)
    else:
        kw.setdefault("altitude", dist)
        kw.setdefault("baseline", 0.15 * dist)
    return rig_preset(
        preset, target=target, proj_size=tuple(proj_size), cam_size=tuple(cam_size), fov_x=fov, **kw
    )
