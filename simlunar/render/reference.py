"""Pure-NumPy reference BRDFs: Lambert, lunar-Lambert (McEwen 1991), Oren-Nayar (1994), Hapke
(2002/2012 form) and the LROC Empirical photometric function (ISIS ``lronacpho``).

These are the ground truth the Mitsuba plugins (:mod:`simlunar.render.bsdfs`) are tested
against, and they can be used on their own (e.g. to shade a DEM analytically). The Hapke
model is :mod:`simlunar.render.reference_hapke`'s, re-exported here.

Conventions shared by every function here
-----------------------------------------
- ``wi`` points from the surface towards the light, ``wo`` from the surface towards the viewer;
  both are unit vectors, shape ``(..., 3)``, in any frame (local or world) as long as ``n`` (the
  unit surface normal, ``(..., 3)`` or ``(3,)``) is given in the same frame. Arrays broadcast.
- The returned value is the BRDF ``f`` in 1/sr, *without* the cosine factor: the reflected
  radiance is ``L_o = f * E_perp * cos(theta_i)`` for a collimated beam of irradiance ``E_perp``
  (normal to the beam). Mitsuba's ``BSDF.eval`` returns ``f * cos(theta_o)``; the plugins follow
  Mitsuba, these functions do not.
- ``f = 0`` where the light or the viewer is below the surface (``cos <= 0``).
- Angles are in radians.
"""

from __future__ import annotations

import numpy as np

from simlunar.render._reference_angles import _unit, local_angles
from simlunar.render.reference_hapke import (
    LUNAR_HAPKE,
    HapkeParams,
    hapke,
    hapke_coherent_backscatter,
    hapke_h_function,
    hapke_normal_albedo,
    hapke_phase,
    hapke_w_from_normal_albedo,
)

__all__ = [
    "LROC_EMPIRICAL_B",
    "LROC_EMPIRICAL_STANDARD_DEG",
    "LUNAR_HAPKE",
    "HapkeParams",
    "hapke",
    "hapke_coherent_backscatter",
    "hapke_h_function",
    "hapke_normal_albedo",
    "hapke_phase",
    "hapke_w_from_normal_albedo",
    "lambert",
    "local_angles",
    "lroc_empirical",
    "lroc_empirical_correction",
    "lroc_empirical_if",
    "lunar_lambert",
    "oren_nayar",
    "phase_angle",
]


def lambert(wi, wo, n, albedo=1.0) -> np.ndarray:
    """Lambertian BRDF ``albedo / pi`` above the surface, 0 below.

    Parameters
    ----------
    wi, wo, n : (..., 3) arrays
        See the module conventions.
    albedo : float or (...) array
        Hemispherical (= normal) albedo in [0, 1].

    Returns
    -------
    (...) float64 array, 1/sr.
    """
    cos_i, cos_o, _ = local_angles(wi, wo, n)
    up = (cos_i > 0) & (cos_o > 0)
    return np.where(up, np.asarray(albedo, dtype=np.float64) / np.pi, 0.0)


def lunar_lambert(wi, wo, n, albedo=1.0, L=0.5) -> np.ndarray:
    """Lunar-Lambert BRDF (McEwen 1991, Icarus 92; McEwen 1996, LPSC 27: the photometric
    function ``I/F = A [(1 - L) cos i + 2 L cos i / (cos i + cos e)]``) as a BRDF:

    ``f = albedo / pi ((1 - L) + 2 L / (cos i + cos o))`` above the surface, 0 below.

    ``L = 0`` is Lambert, ``L = 1`` Lommel-Seeliger normalised to ``albedo / pi`` at normal
    incidence and emission (at i = o = 0 the bracket is (1 - L) + 2 L / 2 = 1); every ``L`` gives
    ``albedo / pi`` there, so ``albedo`` is the normal albedo for any ``L``.

    Parameters
    ----------
    wi, wo, n : (..., 3) arrays
        See the module conventions.
    albedo : float or (...) array
        Normal albedo in [0, 1].
    L : float or (...) array
        Limb-darkening weight in [0, 1].

    Returns
    -------
    (...) float64 array, 1/sr.
    """
    cos_i, cos_o, _ = local_angles(wi, wo, n)
    up = (cos_i > 0) & (cos_o > 0)
    L = np.asarray(L, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.asarray(albedo, np.float64) / np.pi * ((1.0 - L) + 2.0 * L / (cos_i + cos_o))
    return np.where(up, f, 0.0)


def _oren_nayar_qualitative(rho, s2, cdp, alpha, tan_beta):
    """The qualitative model ``rho/pi [A + B max(0, cos dphi) sin(alpha) tan(beta)]``."""
    a = 1.0 - 0.5 * s2 / (s2 + 0.33)
    b = 0.45 * s2 / (s2 + 0.09)
    return rho / np.pi * (a + b * np.maximum(cdp, 0.0) * np.sin(alpha) * tan_beta)


def _oren_nayar_full(rho, s2, cdp, alpha, beta, tan_beta):
    """The full model ``f1 + f2`` (C1, C2, C3 and the rho^2 inter-reflection term)."""
    c1 = 1.0 - 0.5 * s2 / (s2 + 0.33)
    k = s2 / (s2 + 0.09)
    c2 = np.where(
        cdp >= 0,
        0.45 * k * np.sin(alpha),
        0.45 * k * (np.sin(alpha) - (2.0 * beta / np.pi) ** 3),
    )
    c3 = 0.125 * k * (4.0 * alpha * beta / np.pi**2) ** 2
    tan_mid = np.tan(np.minimum((alpha + beta) / 2.0, np.pi / 2 - 1e-9))
    f1 = rho / np.pi * (c1 + cdp * c2 * tan_beta + (1.0 - np.abs(cdp)) * c3 * tan_mid)
    f2 = 0.17 * rho**2 / np.pi * s2 / (s2 + 0.13) * (1.0 - cdp * (2.0 * beta / np.pi) ** 2)
    return f1 + f2


def oren_nayar(wi, wo, n, albedo=1.0, sigma=0.0, model: str = "full") -> np.ndarray:
    """Oren-Nayar rough diffuse BRDF (Oren & Nayar, SIGGRAPH 1994, "Generalization of
    Lambert's reflectance model").

    The surface is made of long symmetric V-cavities with Lambertian facets whose slopes are
    normally distributed with zero mean and standard deviation ``sigma`` (radians). With
    ``alpha = max(theta_i, theta_o)``, ``beta = min(theta_i, theta_o)``, ``dphi`` the azimuth
    difference and ``s2 = sigma**2``:

    ``model="full"`` (the paper's functional approximation, including inter-reflections)::

        C1 = 1 - 0.5 s2 / (s2 + 0.33)
        C2 = 0.45 s2/(s2 + 0.09) sin(alpha)                        if cos(dphi) >= 0
             0.45 s2/(s2 + 0.09) (sin(alpha) - (2 beta/pi)^3)      otherwise
        C3 = 0.125 s2/(s2 + 0.09) (4 alpha beta / pi^2)^2
        f1 = rho/pi [C1 + cos(dphi) C2 tan(beta)
                     + (1 - |cos(dphi)|) C3 tan((alpha + beta)/2)]
        f2 = 0.17 rho^2/pi s2/(s2 + 0.13) [1 - cos(dphi) (2 beta/pi)^2]
        f  = f1 + f2

    ``model="qualitative"`` (the paper's simplified form)::

        A = 1 - 0.5 s2/(s2 + 0.33),  B = 0.45 s2/(s2 + 0.09)
        f = rho/pi [A + B max(0, cos(dphi)) sin(alpha) tan(beta)]

    Both reduce to Lambert (``rho / pi``) at ``sigma = 0`` and are reciprocal. Neither is
    exactly energy conserving: near grazing incidence with ``sigma`` about 0.15-0.26 the
    directional albedo exceeds ``rho`` by up to ~4 % (full) or ~1.3 % (qualitative), so it
    stays below 1 only for ``rho <= 0.95`` (tested), which covers real regolith.

    Roughness convention: ``sigma`` is the standard deviation of facet slope *angles* in
    radians, as in the paper. Mitsuba 0.6's ``roughdiffuse`` took a Beckmann-style roughness
    ``alpha`` and used ``sigma = alpha / sqrt(2)``; pass ``sigma = alpha / np.sqrt(2)`` to
    reproduce it.

    Parameters
    ----------
    wi, wo, n : (..., 3) arrays
        See the module conventions.
    albedo : float or (...) array
        Facet albedo ``rho`` in [0, 1].
    sigma : float
        Facet slope standard deviation in radians, ``0 <= sigma < pi/2``.
    model : {"full", "qualitative"}

    Returns
    -------
    (...) float64 array, 1/sr.
    """
    if model not in ("full", "qualitative"):
        raise ValueError(f"unknown Oren-Nayar model {model!r}; valid: full, qualitative")
    sigma = float(sigma)
    if not (0.0 <= sigma < np.pi / 2):
        raise ValueError(f"sigma must be in [0, pi/2) radians, got {sigma}")
    rho = np.asarray(albedo, dtype=np.float64)
    cos_i, cos_o, cdp = local_angles(wi, wo, n)
    up = (cos_i > 0) & (cos_o > 0)
    ti = np.arccos(np.clip(cos_i, -1.0, 1.0))
    to = np.arccos(np.clip(cos_o, -1.0, 1.0))
    alpha = np.maximum(ti, to)
    beta = np.minimum(ti, to)
    # beta < pi/2 wherever up holds; clip keeps tan finite on the masked-out entries
    tan_beta = np.tan(np.minimum(beta, np.pi / 2 - 1e-9))
    if model == "qualitative":
        f = _oren_nayar_qualitative(rho, sigma * sigma, cdp, alpha, tan_beta)
    else:
        f = _oren_nayar_full(rho, sigma * sigma, cdp, alpha, beta, tan_beta)
    return np.where(up, f, 0.0)


# ---------------------------------------------------------------------------------------------
# LROC Empirical (USGS ISIS lronacpho)

#: B0..B6 of the LROC Empirical photometric function, algorithm version 2019 (USGS ISIS
#: ``lronacpho``, ``LROCEmpirical::photometry``; fitted to more than 760 000 LROC NAC image
#: tiles; the phase angle in degrees, ``Units = Degrees`` in its parameter file)
LROC_EMPIRICAL_B = (
    -1.479654495,
    -0.000083528,
    0.012964707,
    -0.237774774,
    0.556075496,
    0.663671460,
    -0.439918609,
)
#: lronacpho's photometric standard (IncRef, EmaRef, PhaRef) = (i, e, a) in degrees
LROC_EMPIRICAL_STANDARD_DEG = (30.0, 0.0, 30.0)


def phase_angle(wi, wo) -> np.ndarray:
    """Phase angle between the directions ``wi`` and ``wo`` (any length; (..., 3)) in radians,
    as ``2 atan2(|u_i - u_o|, |u_i + u_o|)`` of the unit vectors: accurate near 0, where
    ``arccos`` of the dot product loses half the digits (the opposition peak lives there)."""
    ui, uo = _unit(wi), _unit(wo)
    return 2.0 * np.arctan2(np.linalg.norm(ui - uo, axis=-1), np.linalg.norm(ui + uo, axis=-1))


def _lroc_exponent(a_deg, mu, mu0, B) -> np.ndarray:
    """``B0 + B1 a^2 + B2 a + B3 sqrt(a) + B4 mu + B5 mu0 + B6 mu0^2`` (a in degrees)."""
    b0, b1, b2, b3, b4, b5, b6 = (float(v) for v in B)
    a = np.asarray(a_deg, dtype=np.float64)
    return b0 + b1 * a * a + b2 * a + b3 * np.sqrt(a) + b4 * mu + b5 * mu0 + b6 * mu0 * mu0


def lroc_empirical_if(i_deg, e_deg, a_deg, B=LROC_EMPIRICAL_B) -> np.ndarray:
    """The LROC Empirical photometric function (ISIS ``lronacpho``, version 2019) as written::

        F = mu0 / (mu + mu0) exp(B0 + B1 a^2 + B2 a + B3 sqrt(a) + B4 mu + B5 mu0 + B6 mu0^2)

    with ``mu0 = cos i``, ``mu = cos e`` and every angle in degrees: the I/F of the average
    lunar terrain the coefficients were fitted to. ``mu0 / (mu + mu0)`` is the
    Lommel-Seeliger limb darkening; at zero phase (``i = e``) it is 1/2 for every facet.

    Parameters
    ----------
    i_deg, e_deg, a_deg : float or array
        Incidence, emission and phase angles in degrees (``|i - e| <= a <= i + e`` for a real
        geometry; not checked: the formula is evaluated as given).
    B : sequence of 7 floats
        B0..B6 (default :data:`LROC_EMPIRICAL_B`).

    Returns
    -------
    float64 array, I/F (dimensionless).
    """
    mu0 = np.cos(np.radians(np.asarray(i_deg, dtype=np.float64)))
    mu = np.cos(np.radians(np.asarray(e_deg, dtype=np.float64)))
    return mu0 / (mu + mu0) * np.exp(_lroc_exponent(a_deg, mu, mu0, B))


def lroc_empirical_correction(i_deg, e_deg, a_deg, B=LROC_EMPIRICAL_B) -> np.ndarray:
    """lronacpho's correction factor ``F(30, 0, 30) / F(i, e, a)``: an I/F observed at
    ``(i, e, a)`` times this factor is the I/F at the photometric standard
    (:data:`LROC_EMPIRICAL_STANDARD_DEG`); 1 at the standard itself."""
    return lroc_empirical_if(*LROC_EMPIRICAL_STANDARD_DEG, B=B) / lroc_empirical_if(
        i_deg, e_deg, a_deg, B=B
    )


def lroc_empirical(wi, wo, n, albedo=1.0, B=LROC_EMPIRICAL_B) -> np.ndarray:
    """The LROC Empirical photometric function as a BRDF, scaled by a normal albedo.

    A facet of normal albedo ``A`` lit by a collimated beam of irradiance ``E`` (normal to the
    beam) has ``I/F = A F(i, e, a) / F(0, 0, 0)`` (:func:`lroc_empirical_if`): the function's
    angular shape, normalised so that ``I/F = A`` seen and lit from straight above, as
    ``A`` is for the other models here (Lambert, lunar-Lambert and Hapke's normal albedo). Its
    radiance is ``L = E I/F / pi``, so the BRDF ``f = L / (E cos i)`` is::

        f = A / pi * F(i, e, a) / (cos(i) F(0, 0, 0))
          = A / pi * 2 / (mu + mu0) * exp(X(a, mu, mu0) - X(0, 1, 1))

    with ``X`` the exponent of ``F``: ``B0`` cancels (it sets the absolute I/F of the fitted
    terrain, which the albedo grid replaces). The phase angle is in degrees (radians in the
    inputs, converted). The fit is not reciprocal (``B4 != B5``): ``wi`` must point to the
    light and ``wo`` to the viewer. Its directional albedo is 0.32 A at normal incidence and
    rises to 0.46 A at grazing light (quadrature), so it conserves energy for every ``A <= 1``.

    Parameters
    ----------
    wi, wo, n : (..., 3) arrays
        See the module conventions (``wi`` towards the light, ``wo`` towards the viewer).
    albedo : float or (...) array
        Normal albedo (``pi f`` at ``i = e = a = 0``).
    B : sequence of 7 floats
        B0..B6 (default :data:`LROC_EMPIRICAL_B`; B0 has no effect).

    Returns
    -------
    (...) float64 array, 1/sr.
    """
    cos_i, cos_o, _ = local_angles(wi, wo, n)
    up = (cos_i > 0) & (cos_o > 0)
    mu0, mu = np.clip(cos_i, 0.0, 1.0), np.clip(cos_o, 0.0, 1.0)
    a_deg = np.degrees(phase_angle(wi, wo))
    shape = np.exp(_lroc_exponent(a_deg, mu, mu0, B) - _lroc_exponent(0.0, 1.0, 1.0, B))
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.asarray(albedo, np.float64) / np.pi * 2.0 / (mu + mu0) * shape
    return np.where(up, f, 0.0)
