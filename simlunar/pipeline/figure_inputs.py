"""Inputs of a sampling unit's figures: the image panels (a wavelet plan and its reconstruction),
the reconstruction panels (one plan of the study's own planner reconstructed by every
configured reconstruction) and the sparse-mesh renders of the paper's Fig. 4."""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy import ndimage

from simlunar.planner import DEFAULT_PLANNER, MEASURING, ORACLES, plan, strategy_weights
from simlunar.reconstruction import reconstruct, run_reconstruction
from simlunar.render import render
from simlunar.render.materials import OrenNayarBSDF, sigma_map_from_energy
from simlunar.render.scene import luminance
from simlunar.study.protocol import reconstruction_of, reconstruction_options
from simlunar.study.sampling_planners import study_planners
from simlunar.terrain.types import Terrain

__all__ = [
    "RENDER_LOCK",
    "RenderScene",
    "panel_arrays",
    "panel_energy",
    "panel_planner",
    "reconstruction_panel_arrays",
    "sparse_mesh_render",
]

#: Renders of units running concurrently in threads (``LocalPoolExecutor``) take turns: each
#: render already uses every core, and Mitsuba scenes are built and rendered one at a time.
RENDER_LOCK = threading.RLock()


@dataclass(frozen=True, eq=False)
class RenderScene:
    """A scene and its render settings (as the unit renders it)."""

    terrain: Terrain
    camera: object
    lights: list
    bsdf: object
    spp: int
    seed: int
    max_depth: int

    def render(self, terrain: Terrain | None = None, *, bsdf=None):
        """:func:`simlunar.render.render` of this scene with its camera, lights and settings:
        of ``terrain`` in place of its own and with ``bsdf`` in place of its own where given."""
        return render(
            self.terrain if terrain is None else terrain,
            self.camera,
            lights=self.lights,
            bsdf=self.bsdf if bsdf is None else bsdf,
            spp=self.spp,
            seed=self.seed,
            max_depth=self.max_depth,
        )


def panel_energy(image) -> np.ndarray:
    """The map the figures' panels plan from: the default planner's (the wavelet energy),
    float64 (rows, cols)."""
    return strategy_weights(DEFAULT_PLANNER, image)


def panel_arrays(image, depth, energy, density: float, *, rng) -> dict:
    """Arrays for the image panels: wavelet energy, one wavelet plan and its reconstruction.

    ``energy`` is :func:`panel_energy` of ``image`` (float64), the map the plan samples from.
    """
    n = image.size
    k = max(3, round(density * n))
    p = plan(DEFAULT_PLANNER, k, weights=energy, rng=rng)
    pts = p.rc  # index coordinates: cell (r, c) sits at (r, c)
    filled = np.where(np.isfinite(depth), depth, np.nanmean(depth))
    recon = reconstruct(pts, filled[p.rows, p.cols], image.shape)
    return {
        "wavelet_energy": energy.astype(np.float32),
        "plan_rows": np.asarray(p.rows, np.int32),
        "plan_cols": np.asarray(p.cols, np.int32),
        "reconstruction": recon.astype(np.float64),
    }


def panel_planner(strategies: Sequence[str], strategy_options: Mapping) -> str | None:
    """The study's planner label whose plan the reconstruction panels show: the default
    planner (wavelet) when the study ran it, else the first label that plans from the image
    or none (no oracle, which reads the truth, and no multi-round planner, which measures as
    it goes); None when the study has no such label."""
    labels = [str(s) for s in strategies]
    if DEFAULT_PLANNER in labels:
        return DEFAULT_PLANNER
    for lb in labels:
        base = (strategy_options.get(lb) or {}).get("strategy", lb)
        if base not in ORACLES and base not in MEASURING:
            return lb
    return None


def reconstruction_panel_arrays(options, image, depth, density: float, *, guide, rng):
    """One plan of the study's own planner (:func:`panel_planner`) at ``density``,
    reconstructed by every configured reconstruction from the same samples.

    Parameters
    ----------
    options : SamplingStudyOptions
        The study (its strategies, strategy options, reconstructions and ``outside`` policy).
    image, depth : (rows, cols) float
        Guide image and true depth of the guide view (finite).
    density : float
        k / N of the plan (``figures.panel_density``).
    guide : Guide or None
        What the camera saw, for the guided reconstructions (None when none is configured).
    rng : seed or Generator
        Drives the plan.

    Returns
    -------
    (dict, dict)
        Arrays ``recon_panel_rows`` / ``recon_panel_cols`` (int32 (k,)) and
        ``recon_panel_<i>`` (float32 (rows, cols), the i-th reconstruction in the configured
        order); and the meta ``{"recon_panels": {planner, density, k, reconstructions}}``
        that names them. Both empty when the study has no planner to show
        (:func:`panel_planner`). The samples are the true depth at the planned pixels, without
        range noise, as the image panels take them.
    """
    label = panel_planner(options.strategies, options.strategy_options)
    if label is None:
        return {}, {}
    k = max(3, round(density * depth.size))
    kept = {k: v for k, v in options.strategy_options.items() if k == label}
    one = replace(options, strategies=(label,), strategy_options=kept)
    planners, _ = study_planners(one, image, depth, [k], guide=guide)
    rc = np.asarray(planners[label](k, np.random.default_rng(rng)))
    rows, cols = rc[:, 0].astype(np.int64), rc[:, 1].astype(np.int64)
    values = np.asarray(depth, np.float64)[rows, cols]
    recons = reconstruction_options(options.reconstructions, outside=options.outside)
    out = {"recon_panel_rows": rows.astype(np.int32), "recon_panel_cols": cols.astype(np.int32)}
    for i, opts in enumerate(recons.values()):
        rec = run_reconstruction(
            reconstruction_of(opts), rc, values, depth.shape, guide=guide, options=opts
        )
        out[f"recon_panel_{i}"] = np.asarray(rec.heights, np.float32)
    meta = {"planner": label, "density": float(density), "k": int(k),
            "reconstructions": list(recons)}  # fmt: skip
    return out, {"recon_panels": meta}


def _sample_points(p, heights: np.ndarray, holes: np.ndarray) -> np.ndarray:
    """The (n, 2) index coordinates whose heights rebuild the DEM from the plan ``p``.

    Cell (r, c) sits at (r, c). On a DEM with holes (NaN heights, within the documented
    share) a sample planned in a hole reads the nearest cell with a height, and the rebuilt
    terrain keeps the holes of the terrain it rebuilds.
    """
    if not holes.any():
        return p.rc
    _, (near_r, near_c) = ndimage.distance_transform_edt(holes, return_indices=True)
    cells = np.unique(near_r[p.rows, p.cols] * heights.shape[1] + near_c[p.rows, p.cols])
    if len(cells) < 3:  # samples merged into fewer cells than a triangle needs
        cells = np.unique(np.concatenate([cells, np.flatnonzero(~holes)[:3]]))
    return np.column_stack(np.divmod(cells, heights.shape[1])).astype(np.float64)


def sparse_mesh_render(
    scene: RenderScene,
    image,
    *,
    density: float,
    rng,
    sigma_range: tuple[float, float] | None = None,
    threshold: float | None = None,
    energy: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Paper Fig. 4: render the terrain rebuilt from wavelet-planned samples of ``image``.

    ``density * N`` pixels are planned by wavelet energy; for the nadir orthographic camera
    pixel (r, c) is cell (r, c), so those cells' heights are Delaunay-interpolated back to the
    grid and the rebuilt terrain is rendered with the same camera, lights, BSDF and seed
    (constant roughness). With ``sigma_range`` and an Oren-Nayar ``bsdf`` it is rendered a
    second time with the paper's inferred roughness: per cell of the rebuilt DEM (= per mesh
    vertex, through the terrain UVs) the Oren-Nayar sigma is
    :func:`simlunar.render.materials.sigma_map_from_energy` of the guide image's wavelet
    energy, in ``sigma_range``; cells with normalised energy >= ``threshold`` keep the minimum
    (the planner sampled them densely, so their relief is real geometry).

    Parameters
    ----------
    scene : RenderScene
        The scene and render settings of the full-resolution render (nadir orthographic camera).
    image : (rows, cols) float
        Guide image (pixel (r, c) = cell (r, c)).
    density : float
        Sample fraction k / N.
    rng : numpy Generator
        Drives the wavelet plan.
    sigma_range : (float, float) or None
        ``(sigma_min, sigma_max)`` radians; None (or a non-Oren-Nayar ``bsdf``) skips the
        modulated render.
    threshold : float or None
        Normalised-energy threshold above which the geometry is kept metric.
    energy : (rows, cols) float64 or None
        :func:`panel_energy` of ``image`` when already computed (the plan samples from it).

    Returns
    -------
    dict
        ``sparse_mesh_render`` (rows, cols) float32 linear luminance (constant roughness);
        with modulation also ``sparse_mesh_render_rough`` (same, per-cell roughness) and
        ``sparse_mesh_sigma`` (rows, cols) float32 radians.
    """
    terrain, bsdf = scene.terrain, scene.bsdf
    if energy is None:
        energy = panel_energy(image)
    k = max(3, round(density * image.size))
    p = plan(DEFAULT_PLANNER, k, weights=energy, rng=rng)
    heights = np.asarray(terrain.heights, np.float64)
    holes = ~np.isfinite(heights)
    pts = _sample_points(p, heights, holes)
    recon = reconstruct(pts, heights[pts[:, 0].astype(int), pts[:, 1].astype(int)], heights.shape)
    recon[holes] = np.nan
    sparse = Terrain(recon, terrain.albedo, terrain.spacing, terrain.origin)
    bsdfs = {"sparse_mesh_render": bsdf}
    out = {}
    if sigma_range is not None and isinstance(bsdf, OrenNayarBSDF):
        lo, hi = sigma_range
        sigma = sigma_map_from_energy(energy, sigma_min=lo, sigma_max=hi, threshold=threshold)
        bsdfs["sparse_mesh_render_rough"] = OrenNayarBSDF(bsdf.sigma, bsdf.model, sigma_map=sigma)
        out["sparse_mesh_sigma"] = sigma.astype(np.float32)
    # only the renders take the lock: the plan and the reconstruction above run while another
    # unit of a parallel sweep renders
    for name, b in bsdfs.items():
        with RENDER_LOCK:
            radiance = scene.render(sparse, bsdf=b).image
        out[name] = luminance(radiance)
    return out
