"""Per-pixel features of the learned reconstruction: the image stack, signed image detail,
the samples' linear reconstruction and its leave-one-out residuals, the optional shading
detail, and the anchoring of a predicted residual to the samples (split from
:mod:`simlunar.reconstruction.learned`, which re-exports these names)."""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from simlunar.features._stack import FEATURE_NAMES, image_features
from simlunar.features.maps import to_gray
from simlunar.reconstruction.base import RECONSTRUCTIONS, run_reconstruction
from simlunar.reconstruction.delaunay import _check_inputs, loo_residuals, reconstruct

__all__ = [
    "IMAGE_SIGNED",
    "SAMPLE_FEATURES",
    "SHADING_FEATURE",
    "anchor",
    "feature_names",
    "residual_features",
    "sample_scale",
    "shading_heights",
]

#: signed image features: high-pass at (half, one, two) pitches, derivatives at 1 px, pitch / 2
IMAGE_SIGNED = (
    "img_hp_half",
    "img_hp_one",
    "img_hp_two",
    "img_dr_s1",
    "img_dc_s1",
    "img_dr_half",
    "img_dc_half",
)
#: features of the samples and their linear reconstruction
SAMPLE_FEATURES = (
    "lin_detail",
    "lin_dr",
    "lin_dc",
    "lin_slope",
    "lin_laplace",
    "loo_local",
    "dist_pitch",
    "log2_density",
)
#: the optional feature of the registered ``shading`` reconstruction
SHADING_FEATURE = "shading_detail"


def feature_names(with_shading: bool = False) -> tuple[str, ...]:
    """Feature names in column order (image stack, signed image, samples[, shading])."""
    names = (*(f"image_{n}" for n in FEATURE_NAMES), *IMAGE_SIGNED, *SAMPLE_FEATURES)
    return (*names, SHADING_FEATURE) if with_shading else names


def _distinct(points_rc, values):
    """Distinct positions (duplicates averaged, as the linear reconstruction merges them)."""
    uniq, inverse, counts = np.unique(points_rc, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    return uniq, np.bincount(inverse, weights=values, minlength=len(uniq)) / counts


def sample_scale(points_rc, values) -> tuple[float, np.ndarray]:
    """The height unit h of the features: the RMS leave-one-out residual of the samples.

    Parameters
    ----------
    points_rc : ndarray, shape (k, 2)
    values : ndarray, shape (k,)

    Returns
    -------
    (float, ndarray)
        h (same unit as the values; 0 when every sample lies on its neighbours' plane to
        1e-9 of the largest |value|, or there are fewer than 4 distinct samples), and each distinct sample's residual, shape (k',),
        with the distinct positions as computed by ``np.unique(points_rc, axis=0)``.
    """
    pts, vals = _distinct(np.asarray(points_rc, float), np.asarray(values, float))
    loo = loo_residuals(pts, vals) if len(pts) >= 4 else np.zeros(len(pts))
    h = float(np.sqrt(np.mean(loo**2))) if len(loo) else 0.0
    # rounding of a plane's fit (about 1e-16 of the values) is no relief
    return (h if h > 1e-9 * float(np.abs(vals).max(initial=0.0)) else 0.0), loo


def _gray(image) -> np.ndarray:
    g = to_gray(image)
    mean = float(g.mean())
    return g / mean if mean > 0 else g


def _sample_distance(upts: np.ndarray, shape, pitch: float) -> np.ndarray:
    """Distance (px) of every cell to the nearest sampled cell, shape ``shape``; ``4 * pitch``
    everywhere when no sample lies inside the grid."""
    mask = np.ones(shape, dtype=bool)
    cells = np.rint(upts).astype(np.int64)
    inside = (cells >= 0).all(1) & (cells[:, 0] < shape[0]) & (cells[:, 1] < shape[1])
    mask[cells[inside, 0], cells[inside, 1]] = False
    return ndimage.distance_transform_edt(mask) if not mask.all() else np.full(shape, 4 * pitch)


def residual_features(
    image,
    points_rc,
    values,
    *,
    z_lin: np.ndarray | None = None,
    shading: np.ndarray | None = None,
) -> tuple[np.ndarray, float, np.ndarray]:
    """Per-pixel features of the learned residual, :func:`feature_names` in order.

    Parameters
    ----------
    image : ndarray, shape (rows, cols) or (rows, cols, 3)
        Guide image (any intensity scale; divided by its mean), finite.
    points_rc : array_like, shape (k, 2)
        Measured cells (row, col).
    values : array_like, shape (k,)
        Measured heights or depths (m).
    z_lin : ndarray, shape (rows, cols), optional
        The Delaunay-linear reconstruction of the samples (nearest outside the hull); computed
        when not given.
    shading : ndarray, shape (rows, cols), optional
        Heights of the ``shading`` reconstruction: adds the feature ``shading_detail``.

    Returns
    -------
    (features, h, z_lin)
        features float32 (rows * cols, n_features); h the height unit (:func:`sample_scale`,
        m; 1.0 substituted when it is 0 so the features stay finite); z_lin float64
        (rows, cols).
    """
    g = _gray(image)
    shape = g.shape
    pts, vals, _ = _check_inputs(points_rc, values, shape)
    if z_lin is None:
        z_lin = reconstruct(pts, vals, shape)
    z_lin = np.asarray(z_lin, dtype=np.float64)
    if z_lin.shape != shape or not np.isfinite(z_lin).all():
        raise ValueError(f"z_lin must be finite with the image's shape {shape}, got {z_lin.shape}")
    upts, _ = _distinct(pts, vals)
    density = min(1.0, len(upts) / (shape[0] * shape[1]))
    pitch = max(1.0, density**-0.5)
    h, loo = sample_scale(pts, vals)
    unit = h if h > 0 else 1.0

    cols = [image_features(g, pitch=pitch).reshape(-1, len(FEATURE_NAMES))]

    def blur(a, s):
        return ndimage.gaussian_filter(a, s, mode="reflect")

    signed = [g - blur(g, f * pitch) for f in (0.5, 1.0, 2.0)]
    for s in (1.0, 0.5 * pitch):
        signed += [
            ndimage.gaussian_filter(g, s, order=o, mode="reflect") * s for o in ((1, 0), (0, 1))
        ]
    dr, dc = np.gradient(z_lin)
    slope = pitch / unit
    lap = ndimage.gaussian_laplace(z_lin, 0.5 * pitch, mode="nearest") * pitch**2 / unit
    loo_map = reconstruct(upts, np.abs(loo), shape) / unit if len(upts) else np.zeros(shape)
    dist = _sample_distance(upts, shape, pitch)
    sample = [
        (z_lin - ndimage.gaussian_filter(z_lin, pitch, mode="nearest")) / unit,
        dr * slope,
        dc * slope,
        np.hypot(dr, dc) * slope,
        lap,
        loo_map,
        dist / pitch,
        np.full(shape, math.log2(density)),
    ]
    extra = []
    if shading is not None:
        s = np.asarray(shading, dtype=np.float64)
        if s.shape != shape:
            raise ValueError(f"shading must have the image's shape {shape}, got {s.shape}")
        extra = [np.nan_to_num((s - z_lin) / unit, nan=0.0, posinf=0.0, neginf=0.0)]
    stack = np.stack([a.astype(np.float32).ravel() for a in (*signed, *sample, *extra)], axis=1)
    return np.concatenate([cols[0], stack], axis=1), float(h), z_lin


def shading_heights(points_rc, values, shape, *, guide, options: dict | None) -> np.ndarray:
    """Heights of the registered ``shading`` reconstruction (the optional feature's source).

    A ``ValueError`` when no reconstruction ``shading`` is registered.
    """
    if "shading" not in RECONSTRUCTIONS:
        raise ValueError(
            "the learned reconstruction's shading feature needs the reconstruction 'shading', "
            f"which is not registered (have: {', '.join(RECONSTRUCTIONS)})"
        )
    return run_reconstruction(
        "shading", points_rc, values, shape, guide=guide, options=dict(options or {})
    ).heights


def anchor(z_lin, residual, points_rc) -> np.ndarray:
    """``z_lin + residual - L(residual at the samples)``: measured cells keep z_lin's values.

    Parameters
    ----------
    z_lin, residual : ndarray, shape (rows, cols)
    points_rc : ndarray, shape (k, 2)

    Returns
    -------
    ndarray of float64, shape (rows, cols)
    """
    pts = np.asarray(points_rc, dtype=np.float64)
    at = ndimage.map_coordinates(residual, pts.T, order=1, mode="nearest")
    return z_lin + residual - reconstruct(pts, at, residual.shape)
