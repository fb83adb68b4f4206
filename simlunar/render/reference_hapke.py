"""Pure-NumPy reference Hapke BRDF (2002/2012 form, as in the LROC WAC Hapke maps), its parts
(phase function, H function, opposition surges, macroscopic roughness) and the normal albedo
that links a terrain albedo grid to its single-scattering albedo.

The ground truth of the Mitsuba ``hapke`` plugin; the conventions (directions, the BRDF without
the cosine factor, radians) are those of :mod:`simlunar.render.reference`, which re-exports
every name here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.render._reference_angles import _unit, local_angles

__all__ = [
    "LUNAR_HAPKE",
    "HapkeParams",
    "hapke",
    "hapke_coherent_backscatter",
    "hapke_h_function",
    "hapke_normal_albedo",
    "hapke_phase",
    "hapke_w_from_normal_albedo",
]


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
    albedo, params: HapkeParams = LUNAR_HAPKE, *, n_table: int = 4097
) -> np.ndarray:
    """Single-scattering albedo whose Hapke normal albedo equals ``albedo``.

    This is how a terrain albedo grid (normal albedo per cell) drives the Hapke BSDF: each
    point gets the ``w`` that reproduces its normal albedo, the remaining parameters set the
    angular behaviour: every field of ``params`` but ``w`` (e.g.
    ``dataclasses.replace(LUNAR_HAPKE, B0=0.5)``; its ``w`` is not read). Inverted by
    interpolation in a dense monotone table of :func:`hapke_normal_albedo` over ``w`` in
    [0, 1]; albedos above the largest reachable value give ``w = 1``.
    """
    p = params
    ws = np.linspace(0.0, 1.0, n_table)
    an = hapke_normal_albedo(ws, p.b, p.c, p.B0, p.h, p.theta_bar, p.B_C0, p.h_C)
    return np.interp(np.asarray(albedo, dtype=np.float64), an, ws)
