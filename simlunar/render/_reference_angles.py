"""The geometry every NumPy reference BRDF shares (:mod:`simlunar.render.reference`,
:mod:`simlunar.render.reference_hapke`): unit vectors and the local angles of a light, a viewer
and a normal, under the conventions stated in :mod:`simlunar.render.reference`."""

from __future__ import annotations

import numpy as np

__all__ = ["local_angles"]

_EPS = 1e-12


def _unit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), _EPS)


def local_angles(wi, wo, n) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cosines of incidence and emission and the cosine of the azimuth difference.

    Parameters
    ----------
    wi, wo : (..., 3) array
        Unit directions towards the light and towards the viewer.
    n : (..., 3) or (3,) array
        Unit surface normal in the same frame.

    Returns
    -------
    cos_i, cos_o, cos_dphi : (...) arrays
        ``cos_dphi`` is the cosine of the angle between the projections of ``wi`` and ``wo``
        on the tangent plane (1: same side, i.e. backscatter; -1: opposite sides). Where a
        projection vanishes (a direction along the normal) the azimuth is undefined and
        ``cos_dphi`` is set to 0; every model here is independent of it there.
    """
    wi, wo, n = _unit(wi), _unit(wo), _unit(n)
    cos_i = np.sum(wi * n, axis=-1)
    cos_o = np.sum(wo * n, axis=-1)
    ti = wi - cos_i[..., None] * n
    to = wo - cos_o[..., None] * n
    ni = np.linalg.norm(ti, axis=-1)
    no = np.linalg.norm(to, axis=-1)
    ok = (ni > 1e-9) & (no > 1e-9)
    dot = np.sum(ti * to, axis=-1)
    cos_dphi = np.where(ok, dot / np.where(ok, ni * no, 1.0), 0.0)
    return cos_i, cos_o, np.clip(cos_dphi, -1.0, 1.0)
