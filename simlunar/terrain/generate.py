"""Procedural lunar terrain: fBm base + undulating bed + craters + rocks, and albedo.

Order: base surface (fBm + bed) -> craters (oldest first, each partly erasing what lies in its
bowl) -> rocks on top -> albedo. One seed drives everything; each stage gets its own child
stream (``SeedSequence.spawn``) so turning rocks off does not move the craters.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import simlunar.terrain.sfd as sfd
from simlunar.terrain.craters import Crater, extent_radii, place_craters, stamp_craters
from simlunar.terrain.fractal import fbm, undulating_bed
from simlunar.terrain.params import AlbedoParams, RockParams, TerrainParams
from simlunar.terrain.rocks import Rock, place_rocks, stamp_rocks
from simlunar.terrain.types import Terrain

__all__ = ["TerrainResult", "add_rocks", "generate", "make_albedo", "refine", "refined_shape"]


@dataclass(frozen=True, eq=False)
class TerrainResult:
    """A generated terrain and the features placed on it (for labels and checks)."""

    terrain: Terrain
    craters: list[Crater]
    rocks: list[Rock]
    params: TerrainParams


def _seeds(rng, n):
    if isinstance(rng, np.random.Generator):
        return rng.spawn(n)
    ss = rng if isinstance(rng, np.random.SeedSequence) else np.random.SeedSequence(rng)
    return [np.random.default_rng(s) for s in ss.spawn(n)]


def make_albedo(
    shape,
    *,
    spacing: float,
    params: AlbedoParams,
    freshness: np.ndarray | None = None,
    rock_factor: np.ndarray | None = None,
    rng=None,
) -> np.ndarray:
    """Albedo grid: lunar mean with mild variation, brighter fresh ejecta, rock contrast.

    ``a = mean (1 + variation F) (1 + noise N) (1 + ejecta_brightening freshness) rock_factor``,
    clipped to [0.01, 1], with F a unit-RMS fBm field (H = 0.5, roll-off at 64 cells) and N
    per-cell standard normal noise (the paper's terrains carry independent colour per voxel).
    The default mean 0.12 is a typical normal albedo of lunar soil (mare ~0.07-0.10, highlands
    ~0.15-0.2). ``uniform=True`` returns the mean everywhere (ablations).

    Returns
    -------
    (rows, cols) float32 albedo.
    """
    gen = np.random.default_rng(rng)
    rows, cols = shape
    if params.uniform:
        return np.full((rows, cols), params.mean, dtype=np.float32)
    a = np.full((rows, cols), params.mean)
    if params.variation > 0:
        f = fbm(
            (rows, cols),
            spacing=spacing,
            hurst=0.5,
            rms=1.0,
            periodic=False,
            rolloff_m=64 * spacing,
            rng=gen,
        )
        a *= np.clip(1.0 + params.variation * f, 0.2, None)
    if params.noise > 0:
        a *= np.clip(1.0 + params.noise * gen.standard_normal((rows, cols)), 0.2, None)
    if freshness is not None and params.ejecta_brightening > 0:
        a *= 1.0 + params.ejecta_brightening * freshness
    if rock_factor is not None:
        a *= rock_factor
    return np.clip(a, 0.01, 1.0).astype(np.float32)


def generate(params, *, rng=None, scale: float = 1.0, nodata=None) -> TerrainResult:
    """Generate a terrain from :class:`TerrainParams`.

    Parameters
    ----------
    params : TerrainParams
        The generator's parameters (SI units); a preset's come from
        :func:`simlunar.config.translate.preset_params` (presets are read in ``config/`` only).
    rng : seed or Generator
        Same seed -> bit-identical result.
    scale : float in (0, 1]
        Shrink the grid (same spacing, smaller area); see ``TerrainParams.scaled``.
    nodata : (rows, cols) bool array, optional
        Cells to mark as nodata (NaN heights), e.g. to mimic a real DEM's gaps; without it the
        heights are finite everywhere.

    Returns
    -------
    TerrainResult
        ``terrain`` (heights float64 m, albedo float32), ``craters`` (oldest first, including the
        ones centred outside the grid whose blanket reaches in, and invisible degraded ones) and
        ``rocks``.
    """
    if not isinstance(params, TerrainParams):
        raise TypeError(
            f"generate needs TerrainParams, got {type(params).__name__}; for a preset use "
            "simlunar.config.translate.preset_params('aerial_1')"
        )
    p = params.scaled(scale)
    g_base, g_bed, g_crd, g_crp, g_rkd, g_rkp, g_rks, g_alb = _seeds(rng, 8)
    shape = (p.rows, p.cols)
    h = _base_surface(p, g_base, g_bed)
    fresh = np.zeros(shape) if p.albedo.ejecta_brightening > 0 else None
    craters: list[Crater] = []
    if p.craters.enabled:
        craters = _add_craters(h, p, fresh, g_crd, g_crp)
    rocks: list[Rock] = []
    rock_factor = None
    if p.rocks.enabled:
        rocks, rock_factor = _add_rocks(h, p, g_rkd, g_rkp, g_rks)
    if nodata is not None:
        h[_nodata_mask(nodata, shape)] = np.nan
    alb = make_albedo(
        shape,
        spacing=p.spacing,
        params=p.albedo,
        freshness=fresh,
        rock_factor=rock_factor,
        rng=g_alb,
    )
    return TerrainResult(Terrain(h, alb, p.spacing, p.origin), craters, rocks, p)


def _base_surface(p: TerrainParams, g_base, g_bed) -> np.ndarray:
    """fBm heights plus the undulating bed (when it has an amplitude)."""
    shape = (p.rows, p.cols)
    h = fbm(
        shape,
        spacing=p.spacing,
        hurst=p.fractal.hurst,
        rms=p.fractal.rms,
        periodic=p.fractal.periodic,
        rolloff_m=p.fractal.rolloff,
        rng=g_base,
    )
    if p.bed.amplitude > 0:
        h += undulating_bed(
            shape,
            spacing=p.spacing,
            amplitude=p.bed.amplitude,
            wavelength=p.bed.wavelength,
            rng=g_bed,
        )
    return h


def _widened(extent, margin: float) -> tuple[tuple[float, float, float, float], float]:
    """``extent`` (xmin, xmax, ymin, ymax) grown by ``margin`` on every side, and its area."""
    xmin, xmax, ymin, ymax = extent
    ext = (xmin - margin, xmax + margin, ymin - margin, ymax + margin)
    return ext, (ext[1] - ext[0]) * (ext[3] - ext[2])


def _add_craters(h, p: TerrainParams, fresh, g_crd, g_crp) -> list[Crater]:
    """Sample, place and stamp the crater population into ``h`` (and ``fresh``); the craters
    whose footprint reaches the grid, oldest first."""
    c = p.craters
    xmin, xmax, ymin, ymax = p.extent
    # craters centred up to one ejecta radius outside the grid still cut into it
    ext, area = _widened(p.extent, extent_radii(0.0) * c.d_max / 2.0)
    d = sfd.sample_diameters(c.law_fn(), area, c.d_min, c.d_max, rng=g_crd, what="craters")
    craters = place_craters(
        d, extent=ext, diffusivity=c.diffusivity, max_age_myr=c.max_age_myr, rng=g_crp
    )
    # drop the ones whose footprint misses the grid entirely (cheaper lists, same terrain)
    craters = [
        k
        for k in craters
        if (
            xmin - extent_radii(0.0) * k.diameter / 2
            <= k.x
            <= xmax + extent_radii(0.0) * k.diameter / 2
        )
        and (
            ymin - extent_radii(0.0) * k.diameter / 2
            <= k.y
            <= ymax + extent_radii(0.0) * k.diameter / 2
        )
    ]
    stamp_craters(h, craters, spacing=p.spacing, origin=p.origin, freshness=fresh)
    return craters


def _add_rocks(h, p: TerrainParams, g_rkd, g_rkp, g_rks) -> tuple[list[Rock], np.ndarray]:
    """Sample, place and stamp the rocks into ``h``; the rocks and their albedo factor grid."""
    r = p.rocks
    # rocks centred just outside the grid still show their part inside it
    ext, area = _widened(p.extent, 0.7 * r.d_max)
    d = sfd.sample_diameters(r.law_fn(), area, r.d_min, r.d_max, rng=g_rkd, what="rocks")
    rocks = place_rocks(
        d,
        extent=ext,
        cluster_fraction=r.cluster_fraction,
        cluster_radius_m=r.cluster_radius,
        mean_per_cluster=r.mean_per_cluster,
        albedo_contrast=r.albedo_contrast,
        rng=g_rkp,
    )
    rock_factor = np.ones((p.rows, p.cols))
    stamp_rocks(h, rock_factor, rocks, spacing=p.spacing, origin=p.origin, rng=g_rks)
    return rocks, rock_factor


def add_rocks(terrain: Terrain, rocks: RockParams, *, rng=None) -> tuple[Terrain, list[Rock]]:
    """A terrain with ``rocks`` stamped on it as :func:`generate` stamps them (a DEM's
    surface, which resolves no rocks, given the population of a size-frequency model).

    The diameters are drawn over the terrain's extent widened by the largest rock (so rocks
    centred just outside show their part inside), placed and stamped with the generator's
    three rock streams, here the children of ``rng``; the albedo is multiplied by the rocks'
    factor (``albedo_contrast`` on each rock). NaN heights (nodata) stay NaN. Returns the new
    terrain (float64 heights, float32 albedo, the same grid and CRS) and the rocks.
    """
    if not rocks.enabled:
        return terrain, []
    g_rkd, g_rkp, g_rks = _seeds(rng, 3)
    rows, cols = terrain.shape
    p = TerrainParams(rows=rows, cols=cols, spacing=float(terrain.spacing),
                      origin=tuple(map(float, terrain.origin)), rocks=rocks)  # fmt: skip
    h = np.array(terrain.heights, dtype=np.float64, copy=True)
    placed, factor = _add_rocks(h, p, g_rkd, g_rkp, g_rks)
    albedo = (np.asarray(terrain.albedo, np.float64) * factor).astype(np.float32)
    return Terrain(h, albedo, terrain.spacing, terrain.origin, crs=terrain.crs), placed


def refined_shape(shape, spacing: float, finer: float) -> tuple[int, int]:
    """(rows, cols) of whole cells of ``finer`` m over a grid of ``shape`` cells of
    ``spacing`` m (:func:`refine`'s grid)."""
    rows, cols = (int(np.floor(n * spacing / finer + 1e-9)) for n in shape)
    return rows, cols


def refine(terrain: Terrain, spacing: float) -> Terrain:
    """The terrain on finer square cells of ``spacing`` m over the same extent (as many whole
    cells as fit), heights and albedo interpolated bilinearly between the old cell centres
    (clamped at the border; a NaN cell makes its neighbourhood NaN): a DEM's surface made fine
    enough to carry rocks (:func:`add_rocks`), with no detail it did not have."""
    from scipy import ndimage

    old = float(terrain.spacing)
    if not (np.isfinite(spacing) and 0 < spacing <= old):
        raise ValueError(f"refine: spacing must be in (0, {old:g}] m (finer), got {spacing}")
    rows, cols = terrain.shape
    n_r, n_c = refined_shape(terrain.shape, old, spacing)
    # new cell centres in the old grid's index coordinates (centre of old cell i at i)
    r = (np.arange(n_r) + 0.5) * spacing / old - 0.5
    c = (np.arange(n_c) + 0.5) * spacing / old - 0.5
    rr, cc = np.meshgrid(np.clip(r, 0, rows - 1), np.clip(c, 0, cols - 1), indexing="ij")

    def lerp(a):
        return ndimage.map_coordinates(np.asarray(a, np.float64), [rr, cc], order=1, mode="nearest")

    return Terrain(lerp(terrain.heights), lerp(terrain.albedo).astype(np.float32), spacing,
                   terrain.origin, crs=terrain.crs)  # fmt: skip


def _nodata_mask(nodata, shape) -> np.ndarray:
    """``nodata`` checked to be a boolean mask of the grid's ``shape``."""
    mask = np.asarray(nodata)
    if mask.shape != shape or mask.dtype != bool:
        raise ValueError(
            f"nodata must be a boolean mask of shape {shape}, got {mask.dtype} {mask.shape}"
        )
    return mask
