"""Pure-NumPy reference BRDFs: Lambert, lunar-Lambert (McEwen 1991), Oren-Nayar (1994), Hapke
(2002/2012 form) and the LROC Empirical photometric function (ISIS ``lronacpho``).

These are the ground truth the Mitsuba plugins (:mod:`simlunar.render.bsdfs`) are tested
against, and they can be used on their own (e.g. to shade a DEM analytically).

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

from dataclasses import dataclass

import numpy as np

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
# Hapke


@dataclass(frozen=True)
class HapkeParams:
    """Hapke model parameters (angles in radians).

    Attributes
    ----------
    w : float
        Single-scattering albedo in [0, 1] (:func:`hapke` also takes a per-point array).
    b : float
        Henyey-Greenstein lobe width parameter in [0, 1).
    c : float
        Lobe weight in [-1, 1]: backscatter lobe weight (1 + c)/2, forward (1 - c)/2
        (Hapke 2012 convention).
    B0 : float
        Shadow-hiding opposition surge amplitude ``B_S0`` (>= 0).
    h : float
        Shadow-hiding opposition surge angular width ``h_S`` (> 0).
    theta_bar : float
        Mean macroscopic slope angle in radians, [0, pi/2).
    B_C0 : float
        Coherent-backscatter opposition surge amplitude (>= 0; 0, the default, leaves it out).
    h_C : float
        Coherent-backscatter opposition surge angular width (> 0; no effect when ``B_C0 = 0``).
    """

    w: float
    b: float
    c: float
    B0: float
    h: float
    theta_bar: float
    B_C0: float = 0.0
    h_C: float = 0.03


#: Lunar defaults. Provenance and honesty about each number:
#:
#: - ``theta_bar = 23.657 deg``: the mean slope held fixed for every tile of the LROC WAC Hapke
#:   parameter maps (Sato, Robinson, Hapke, Denevi & Boyd 2014, "Resolved Hapke parameter maps
#:   of the Moon", JGR Planets 119, 1775-1805, doi:10.1002/2013JE004580). Read from secondary
#:   sources quoting the map product's README (WAC_HAPKEPARAMMAP), not from the paper itself.
#:   Those maps also fix the coherent-backscatter amplitude to 0 and the porosity factor K to 1,
#:   which is the form implemented here (shadow hiding only, K = 1).
#: - ``b = 0.26, c = 0.08``: mare values at 643 nm attributed to Sato et al. (2014) by a
#:   secondary source; NOT verified against the paper's tables. They are consistent with
#:   Hapke's (2012, Icarus 221, 1079) "hockey stick" relation c = 3.29 exp(-17.4 b^2) - 0.908
#:   (which gives c = 0.11 at b = 0.26; the relation is quoted from memory, unverified).
#: - ``B0 = 1.0, h = 0.07``: typical of published lunar shadow-hiding fits (unverified; Sato et
#:   al. fit Bs0 and hs per tile and their medians could not be checked here).
#: - ``w = 0.25``: a visible-light lunar single-scattering albedo of the right order
#:   (unverified). In scenes ``w`` normally comes from the terrain albedo grid instead
#:   (see :func:`hapke_w_from_normal_albedo`).
#: - ``B_C0 = 0``: no coherent backscatter, as in the Sato et al. (2014) maps. Hapke, Denevi,
#:   Sato, Braden & Robinson (2012, "The wavelength dependence of the lunar phase curve as seen
#:   by the LROC wide-angle camera", JGR 117, E00H15, doi:10.1029/2011JE003916) need it: it is
#:   nearly 40 % of the highlands' opposition effect in the UV and over 60 % in the red (their
#:   abstract; their fitted amplitudes and widths were not read here).
#: - ``h_C = 0.03``: an assumed width (unverified), used only when ``B_C0 > 0``: the coherent
#:   peak ``B_C`` falls to half at ``tan(g/2) = 0.3568 h_C``, i.e. g = 1.23 deg, of the order of
#:   the 1.2-3.9 deg widths of the lunar coherent-backscatter peak that Velikodsky et al. (2016,
#:   Icarus 275, 1-15, "Opposition effect of the Moon from LROC WAC data") report by their own
#:   definition.
LUNAR_HAPKE = HapkeParams(
    w=0.25, b=0.26, c=0.08, B0=1.0, h=0.07, theta_bar=float(np.deg2rad(23.657)), B_C0=0.0, h_C=0.03
)


def hapke_phase(cos_g, b, c) -> np.ndarray:
    """Double Henyey-Greenstein particle phase function ``p(g)`` (Hapke 2012 convention).

    ``p = (1+c)/2 (1-b^2)/(1 - 2b cos g + b^2)^1.5 + (1-c)/2 (1-b^2)/(1 + 2b cos g + b^2)^1.5``
    with ``g`` the phase angle (0 = backscatter). Normalised so that its mean over the sphere
    is 1.
    """
    cg = np.asarray(cos_g, dtype=np.float64)
    b2 = b * b
    back = (1 - b2) / (1 - 2 * b * cg + b2) ** 1.5
    fwd = (1 - b2) / (1 + 2 * b * cg + b2) ** 1.5
    return (1 + c) / 2 * back + (1 - c) / 2 * fwd


def hapke_coherent_backscatter(tan_half_g, h_C) -> np.ndarray:
    """Hapke's coherent-backscatter opposition function ``B_C(g)`` (Hapke 2002, Icarus 157,
    523, eq. 32; Hapke 2012, "Theory of reflectance and emittance spectroscopy", 2nd ed.)::

        B_C(g) = [1 + (1 - exp(-x)) / x] / [2 (1 + x)^2],   x = tan(g/2) / h_C

    ``B_C(0) = 1`` (the limit ``(1 - exp(-x)) / x -> 1``, used below ``x = 1e-6``) and it
    falls to 1/2 at ``x = 0.3568``. The reflectance is multiplied by ``1 + B_C0 B_C(g)``.
    """
    x = np.asarray(tan_half_g, dtype=np.float64) / h_C
    small = x < 1e-6
    xs = np.where(small, 1.0, x)
    ratio = np.where(small, 1.0 - 0.5 * x, -np.expm1(-xs) / xs)
    return (1.0 + ratio) / (2.0 * (1.0 + x) ** 2)


def hapke_h_function(x, w) -> np.ndarray:
    """Hapke's (2002, Icarus 157, 523) approximation of Chandrasekhar's H function.

    ``H(x) = 1 / (1 - w x [r0 + (1 - 2 r0 x)/2 ln((1 + x)/x)])`` with
    ``r0 = (1 - gamma)/(1 + gamma)``, ``gamma = sqrt(1 - w)``; accurate to about 1 %.
    """
    x = np.maximum(np.asarray(x, dtype=np.float64), 1e-9)
    w = np.asarray(w, dtype=np.float64)
    gamma = np.sqrt(np.clip(1.0 - w, 0.0, 1.0))
    r0 = (1 - gamma) / (1 + gamma)
    return 1.0 / (1.0 - w * x * (r0 + (1 - 2 * r0 * x) / 2 * np.log((1 + x) / x)))


def _roughness(cos_i, cos_e, cos_psi, theta_bar):
    """Hapke (1984, Icarus 59, 41) macroscopic roughness: effective cosines and shadowing S.

    Returns ``(mu0e, mue, S)``. ``cos_psi`` is the cosine of the azimuth difference
    (1 = same side). Both of Hapke's cases (i <= e and e <= i) are evaluated and the right
    one is selected, which keeps the expression reciprocal.
    """
    mu0 = np.clip(cos_i, 1e-9, 1.0)
    mu = np.clip(cos_e, 1e-9, 1.0)
    if theta_bar <= 0.0:
        one = np.ones(np.broadcast(mu0, mu, cos_psi).shape)
        return mu0 * one, mu * one, one
    si = np.sqrt(1 - mu0**2)
    se = np.sqrt(1 - mu**2)
    psi = np.arccos(np.clip(cos_psi, -1.0, 1.0))
    tb = np.tan(theta_bar)
    cot_tb = 1.0 / tb
    chi = 1.0 / np.sqrt(1.0 + np.pi * tb * tb)
    cot_i = mu0 / np.maximum(si, 1e-9)
    cot_e = mu / np.maximum(se, 1e-9)
    e1i = np.exp(-2.0 / np.pi * cot_tb * cot_i)
    e1e = np.exp(-2.0 / np.pi * cot_tb * cot_e)
    e2i = np.exp(-1.0 / np.pi * cot_tb**2 * cot_i**2)
    e2e = np.exp(-1.0 / np.pi * cot_tb**2 * cot_e**2)
    eta_i = chi * (mu0 + si * tb * e2i / (2.0 - e1i))
    eta_e = chi * (mu + se * tb * e2e / (2.0 - e1e))
    s2 = np.sin(psi / 2) ** 2
    f = np.exp(-2.0 * np.tan(np.minimum(psi, np.pi - 1e-6) / 2))
    cpsi = np.cos(psi)
    # case i <= e
    d1 = 2.0 - e1e - psi / np.pi * e1i
    mu0e_1 = chi * (mu0 + si * tb * (cpsi * e2e + s2 * e2i) / d1)
    mue_1 = chi * (mu + se * tb * (e2e - s2 * e2i) / d1)
    s_1 = mue_1 / eta_e * mu0 / eta_i * chi / (1 - f + f * chi * mu0 / eta_i)
    # case e <= i
    d2 = 2.0 - e1i - psi / np.pi * e1e
    mu0e_2 = chi * (mu0 + si * tb * (e2i - s2 * e2e) / d2)
    mue_2 = chi * (mu + se * tb * (cpsi * e2i + s2 * e2e) / d2)
    s_2 = mue_2 / eta_e * mu0 / eta_i * chi / (1 - f + f * chi * mu / eta_e)
    first = mu0 >= mu  # i <= e
    return (
        np.where(first, mu0e_1, mu0e_2),
        np.where(first, mue_1, mue_2),
        np.where(first, s_1, s_2),
    )


def hapke(wi, wo, n, params: HapkeParams = LUNAR_HAPKE) -> np.ndarray:
    """Hapke BRDF in the form used for the LROC WAC Hapke maps (Sato et al. 2014), with the
    coherent-backscatter opposition effect of Hapke (2002, 2012) as an option.

    Bidirectional reflectance (Hapke 2012, porosity factor K = 1, isotropic multiple
    scattering ``H H - 1`` and the 1984 macroscopic-roughness correction)::

        r = w/(4 pi) mu0e/(mu0e + mue) [p(g) (1 + B0 B_S(g)) + H(mu0e) H(mue) - 1]
            * (1 + B_C0 B_C(g)) S(i, e, psi)
        B_S(g) = 1 / (1 + tan(g/2) / h)                       (shadow hiding, B0 = B_S0)
        B_C(g) = :func:`hapke_coherent_backscatter` (tan(g/2), h_C)   (coherent backscatter)

    and the BRDF is ``f = r / cos(i)``. At zero phase both surges are at their peak
    (``B_S = B_C = 1``): the single-scattering term gains ``1 + B0`` and the whole reflectance
    ``1 + B_C0``. With ``B_C0 = 0`` (the default) this is the Sato et al. (2014) form. ``g`` is the phase angle between ``wi`` and ``wo``
    (``cos g = wi . wo``), so the opposition surge peaks when light and viewer coincide
    (camera-centred light). The model is reciprocal. It is not strictly energy conserving:
    the surge adds light, so with ``w = 1`` and a strong backscatter lobe the directional
    albedo can exceed 1; for ``w <= 0.95`` it stays below 1 (tested).

    Parameters
    ----------
    wi, wo, n : (..., 3) arrays
        See the module conventions.
    params : HapkeParams
        ``w`` (single-scattering albedo in [0, 1], a float or a (...) array, e.g.
        ``dataclasses.replace(LUNAR_HAPKE, w=w_grid)``), ``b``, ``c`` (double Henyey-Greenstein,
        :func:`hapke_phase`), ``B0``, ``h`` (opposition surge amplitude >= 0 and width > 0) and
        ``theta_bar`` (mean macroscopic slope angle in radians), ``B_C0``, ``h_C``
        (coherent-backscatter amplitude >= 0 and width > 0).

    Returns
    -------
    (...) float64 array, 1/sr.
    """
    wi_u, wo_u = _unit(wi), _unit(wo)
    cos_i, cos_e, cos_psi = local_angles(wi_u, wo_u, n)
    up = (cos_i > 0) & (cos_e > 0)
    cos_g = np.clip(np.sum(wi_u * wo_u, axis=-1), -1.0, 1.0)
    mu0e, mue, S = _roughness(cos_i, cos_e, cos_psi, float(params.theta_bar))
    w = np.asarray(params.w, dtype=np.float64)
    # |wi - wo| / |wi + wo| = tan(g/2), accurate near g = 0 where the surge peaks
    tan_half_g = np.linalg.norm(wi_u - wo_u, axis=-1) / np.maximum(
        np.linalg.norm(wi_u + wo_u, axis=-1), 1e-12
    )
    surge = 1.0 + params.B0 / (1.0 + tan_half_g / params.h)
    coherent = 1.0 + params.B_C0 * hapke_coherent_backscatter(tan_half_g, params.h_C)
    multiple = hapke_h_function(mu0e, w) * hapke_h_function(mue, w) - 1.0
    phase = hapke_phase(cos_g, params.b, params.c)
    r = w / (4 * np.pi) * mu0e / (mu0e + mue) * (phase * surge + multiple) * coherent * S
    return np.where(up, r / np.maximum(cos_i, 1e-9), 0.0)


def hapke_normal_albedo(
    w,
    b=LUNAR_HAPKE.b,
    c=LUNAR_HAPKE.c,
    B0=LUNAR_HAPKE.B0,
    h=LUNAR_HAPKE.h,
    theta_bar=LUNAR_HAPKE.theta_bar,
    B_C0=LUNAR_HAPKE.B_C0,
    h_C=LUNAR_HAPKE.h_C,
) -> np.ndarray:
    """Normal albedo ``pi * f`` at ``i = e = g = 0`` (radiance factor of a surface seen and
    lit from straight above), as a function of the single-scattering albedo ``w``.

    At normal incidence the roughness correction gives ``mu0e = mue = chi(theta_bar)`` and
    ``S = 1``, so ``A_n = w/8 [p(0)(1 + B0) + H(chi)^2 - 1] (1 + B_C0)``; increasing in ``w``.
    """
    del h, h_C  # B_S(0) = B_C(0) = 1 whatever the widths
    w = np.asarray(w, dtype=np.float64)
    chi = 1.0 / np.sqrt(1.0 + np.pi * np.tan(theta_bar) ** 2)
    single = hapke_phase(1.0, b, c) * (1 + B0)
    return w / 8.0 * (single + hapke_h_function(chi, w) ** 2 - 1.0) * (1 + B_C0)


def hapke_w_from_normal_albedo(
    albedo,
    b=LUNAR_HAPKE.b,
    c=LUNAR_HAPKE.c,
    B0=LUNAR_HAPKE.B0,
    h=LUNAR_HAPKE.h,
    theta_bar=LUNAR_HAPKE.theta_bar,
    B_C0=LUNAR_HAPKE.B_C0,
    h_C=LUNAR_HAPKE.h_C,
    n_table: int = 4097,
) -> np.ndarray:
    """Single-scattering albedo whose Hapke normal albedo equals ``albedo``.

    This is how a terrain albedo grid (normal albedo per cell) drives the Hapke BSDF: each
    point gets the ``w`` that reproduces its normal albedo, the remaining parameters set the
    angular behaviour. Inverted by interpolation in a dense monotone table of
    :func:`hapke_normal_albedo` over ``w`` in [0, 1]; albedos above the largest reachable
    value give ``w = 1``.
    """
    ws = np.linspace(0.0, 1.0, n_table)
    an = hapke_normal_albedo(ws, b, c, B0, h, theta_bar, B_C0, h_C)
    return np.interp(np.asarray(albedo, dtype=np.float64), an, ws)


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
