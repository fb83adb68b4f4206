"""The NumPy reference BRDFs (simlunar/render/reference.py): limits, symmetries, energy and
hand-computed values of Lambert, lunar-Lambert, Oren-Nayar and Hapke, and the geometry helper
``local_angles``. Pure NumPy: nothing here needs Mitsuba."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simlunar.render import reference as R
from tests.render.test_bsdfs import angle_grid

N_UP = np.array([0.0, 0.0, 1.0])


def sph(theta, phi=0.0):
    """Unit vector(s) from polar angle theta and azimuth phi (radians), z up."""
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)


def lunar(**changes) -> R.HapkeParams:
    """The lunar Hapke parameters with ``changes``."""
    return dataclasses.replace(R.LUNAR_HAPKE, **changes)


def upper_dirs(rng, k):
    v = rng.normal(size=(k, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2]) + 1e-3
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def directional_albedo(fn, theta_i, n=256, **kw):
    """int f(wi, wo) cos(theta_o) dwo by the midpoint rule in (cos theta_o, phi_o)."""
    mu = (np.arange(n) + 0.5) / n
    ph = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    M, P = np.meshgrid(mu, ph, indexing="ij")
    s = np.sqrt(1 - M**2)
    wo = np.stack([s * np.cos(P), s * np.sin(P), M], -1)
    wi = np.broadcast_to(sph(theta_i), wo.shape)
    f = fn(wi, wo, N_UP, **kw)
    return float(np.sum(f * M) / n * (2 * np.pi / (2 * n)))


MODELS = [
    (R.lunar_lambert, dict(albedo=0.3, L=0.6)),
    (R.oren_nayar, dict(albedo=0.8, sigma=0.4)),
    (R.oren_nayar, dict(albedo=0.9, sigma=1.2)),
    (R.oren_nayar, dict(albedo=0.8, sigma=0.4, model="qualitative")),
    (R.hapke, {}),
    (R.hapke, dict(params=lunar(w=0.9, B0=2.0, h=0.03, theta_bar=0.6, b=0.4, c=-0.3))),
    (R.hapke, dict(params=lunar(w=0.5, theta_bar=0.0))),
]


# --- Lambert and the sigma = 0 limit -------------------------------------------------------


def test_lambert_value_and_horizon():
    wi, wo = sph([0.3, 1.2, 2.0]), sph([0.5, 0.1, 0.4])
    np.testing.assert_allclose(R.lambert(wi, wo, N_UP, 0.6), [0.6 / np.pi, 0.6 / np.pi, 0.0])


@pytest.mark.parametrize("model", ["full", "qualitative"])
def test_oren_nayar_sigma_zero_is_lambert(rng, model):
    wi, wo = upper_dirs(rng, 500), upper_dirs(rng, 500)
    albedo = rng.uniform(0, 1, 500)
    np.testing.assert_allclose(
        R.oren_nayar(wi, wo, N_UP, albedo, 0.0, model), R.lambert(wi, wo, N_UP, albedo), rtol=1e-12
    )


def test_frame_independence(rng):
    """The same geometry in a rotated frame gives the same value."""
    wi, wo = upper_dirs(rng, 50), upper_dirs(rng, 50)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    for fn, kw in MODELS:
        a = fn(wi, wo, N_UP, **kw)
        b = fn(wi @ q.T, wo @ q.T, q @ N_UP, **kw)
        np.testing.assert_allclose(a, b, rtol=1e-9, err_msg=f"{fn.__name__} {kw}")


# --- reciprocity and energy -----------------------------------------------------------------


@pytest.mark.parametrize(("fn", "kw"), MODELS)
def test_reciprocity(rng, fn, kw):
    wi, wo = upper_dirs(rng, 2000), upper_dirs(rng, 2000)
    np.testing.assert_allclose(fn(wi, wo, N_UP, **kw), fn(wo, wi, N_UP, **kw), rtol=1e-10)


@pytest.mark.parametrize(("fn", "kw"), MODELS)
def test_zero_below_horizon(fn, kw):
    wi = sph([0.4, 1.7, 0.4])
    wo = sph([1.8, 0.3, 0.5], [0.0, 0.0, np.pi])
    f = fn(wi, wo, N_UP, **kw)
    assert f[0] == 0.0 and f[1] == 0.0 and f[2] > 0.0


def test_quadrature_is_exact_enough_for_lambert():
    # sanity check of the integrator used below: a white Lambertian surface reflects everything
    assert directional_albedo(R.lambert, 0.7, albedo=1.0) == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("model", ["full", "qualitative"])
@pytest.mark.parametrize("sigma", [0.15, 0.25, 0.6, 1.0, 1.5])
def test_oren_nayar_directional_albedo_at_most_one(model, sigma):
    # The 1994 functional approximation is not exactly energy conserving: with rho = 1 it
    # reflects up to ~4 % (full) / ~1.3 % (qualitative) more than it receives near grazing
    # incidence (sigma ~ 0.15-0.26, theta_i -> 90 deg; scanned while writing this test). So
    # albedo <= 1 holds for rho <= 0.95, which covers every physical regolith albedo.
    for theta_i in (0.0, 0.6, 1.2, 1.5, 1.55):
        a = directional_albedo(R.oren_nayar, theta_i, albedo=0.95, sigma=sigma, model=model)
        assert 0.45 < a <= 1.0, (theta_i, a)
        a1 = directional_albedo(R.oren_nayar, theta_i, albedo=1.0, sigma=sigma, model=model)
        assert a1 <= 1.05, (theta_i, a1)


@pytest.mark.parametrize(
    "kw",
    [
        dict(w=1.0),
        dict(w=0.95, B0=1.0, theta_bar=0.0),
        dict(w=0.95, b=0.6, c=1.0, B0=1.0),
        dict(w=0.95, b=0.6, c=1.0, B0=1.0, theta_bar=0.0),
    ],
)
def test_hapke_directional_albedo_at_most_one(kw):
    # Hapke's surge multiplies the single-scattering term without taking energy elsewhere, so
    # with w = 1 AND a strong backscatter lobe plus surge the model reflects more than it
    # receives (1.08-1.28 measured while writing this test); for w <= 0.95 it stays below 1
    for theta_i in (0.0, 0.6, 1.2, 1.5):
        a = directional_albedo(R.hapke, theta_i, params=lunar(**kw))
        assert 0.0 < a <= 1.0, (theta_i, a)


# --- hand-computed Oren-Nayar values --------------------------------------------------------
# theta_i = 60 deg, theta_o = 30 deg, sigma = 0.5 (s2 = 0.25), so alpha = pi/3, beta = pi/6:
#   A = C1 = 1 - 0.5 * 0.25/0.58 = 0.7844828;  k = 0.25/0.34 = 0.7352941;  B = 0.45 k = 0.3308824
#   sin(alpha) tan(beta) = (sqrt(3)/2)(1/sqrt(3)) = 0.5
#   C3 = 0.125 k (4 alpha beta/pi^2)^2 = 0.125 k (2/9)^2 = 0.0045389
#   inter-reflection factor 0.17 s2/(s2 + 0.13) = 0.1118421;  (2 beta/pi)^2 = 1/9


def test_oren_nayar_qualitative_hand_value():
    # dphi = 0: f = rho/pi (A + B * 0.5) = rho/pi * 0.9499239
    f = R.oren_nayar(sph(np.pi / 3), sph(np.pi / 6), N_UP, 1.0, 0.5, "qualitative")
    assert f == pytest.approx(0.9499239 / np.pi, rel=1e-6)
    # dphi = 180 deg: the B term is clipped by max(0, cos dphi) -> rho/pi A
    f = R.oren_nayar(sph(np.pi / 3), sph(np.pi / 6, np.pi), N_UP, 1.0, 0.5, "qualitative")
    assert f == pytest.approx(0.7844828 / np.pi, rel=1e-6)


def test_oren_nayar_full_hand_values():
    rho = 0.5
    wi = sph(np.pi / 3)
    # dphi = 0: f1 = rho/pi (C1 + C2 tan b) = rho/pi 0.9499239; f2 = rho^2/pi 0.1118421 (8/9)
    f = R.oren_nayar(wi, sph(np.pi / 6), N_UP, rho, 0.5)
    assert f == pytest.approx((rho * 0.9499239 + rho**2 * 0.1118421 * 8 / 9) / np.pi, rel=1e-6)
    # dphi = 90 deg: f1 = rho/pi (C1 + C3 tan 45deg); f2 = rho^2/pi 0.1118421
    f = R.oren_nayar(wi, sph(np.pi / 6, np.pi / 2), N_UP, rho, 0.5)
    assert f == pytest.approx(
        (rho * (0.7844828 + 0.0045389) + rho**2 * 0.1118421) / np.pi, rel=1e-6
    )
    # dphi = 180 deg: C2 = B (sin a - (2b/pi)^3) = 0.3308824 (0.8660254 - 1/27) = 0.2742969
    # f1 = rho/pi (C1 - C2 tan b) = rho/pi (0.7844828 - 0.1583653); f2 = rho^2/pi 0.1118421 (10/9)
    f = R.oren_nayar(wi, sph(np.pi / 6, np.pi), N_UP, rho, 0.5)
    assert f == pytest.approx((rho * 0.6261175 + rho**2 * 0.1118421 * 10 / 9) / np.pi, rel=1e-6)


def test_oren_nayar_retroreflects_more_than_lambert():
    # the model's hallmark: rough surfaces look brighter towards the light (backscatter)
    wi = sph(1.0)
    back = R.oren_nayar(wi, sph(1.0, 0.0), N_UP, 1.0, 0.5)
    fwd = R.oren_nayar(wi, sph(1.0, np.pi), N_UP, 1.0, 0.5)
    assert back > 1.0 / np.pi > fwd


def test_oren_nayar_mitsuba06_roughness_convention():
    # Mitsuba 0.6 roughdiffuse alpha = sqrt(2) sigma: documented, reproduced by conversion
    alpha = 0.5
    f = R.oren_nayar(sph(0.9), sph(0.4, 0.3), N_UP, 1.0, alpha / np.sqrt(2))
    g = R.oren_nayar(sph(0.9), sph(0.4, 0.3), N_UP, 1.0, 0.35355339)
    assert f == pytest.approx(g, rel=1e-7)


@pytest.mark.parametrize(
    ("kw", "msg"),
    [
        (dict(sigma=-0.1), "sigma"),
        (dict(sigma=np.pi / 2), "sigma"),
        (dict(sigma=0.2, model="nope"), "full, qualitative"),
    ],
)
def test_oren_nayar_errors(kw, msg):
    with pytest.raises(ValueError, match=msg):
        R.oren_nayar(sph(0.1), sph(0.2), N_UP, 1.0, **kw)


# --- Hapke ----------------------------------------------------------------------------------


def test_hg_phase_function_is_normalised():
    # mean of p over the sphere is 1 for any (b, c)
    mu = np.linspace(-1, 1, 200001)
    for b, c in [(0.26, 0.08), (0.6, -0.5), (0.1, 1.0)]:
        p = R.hapke_phase(mu, b, c)
        assert np.trapezoid(p, mu) / 2 == pytest.approx(1.0, rel=1e-5)
    # c = 1: pure backscatter lobe peaks at g = 0 with (1 + b)/(1 - b)^2
    assert R.hapke_phase(1.0, 0.5, 1.0) == pytest.approx(1.5 / 0.25)


def test_h_function_against_chandrasekhar():
    # Chandrasekhar (1960) conservative isotropic scattering: H(1) = 2.90781; Hapke's (2002)
    # approximation claims ~1 %. By hand: r0 = 1, H(1) = 1 / (0.5 ln 2) = 2.885390
    assert R.hapke_h_function(1.0, 1.0) == pytest.approx(1 / (0.5 * np.log(2)), rel=1e-12)
    assert R.hapke_h_function(1.0, 1.0) == pytest.approx(2.90781, rel=0.01)
    assert R.hapke_h_function(0.5, 0.0) == 1.0  # no scattering, no multiple scattering


def test_hapke_hand_value_at_normal_geometry():
    # theta_bar = 0, isotropic particles (b = 0), no surge, w = 1, i = e = g = 0:
    # f = w/(4 pi) * 1/(1 + 1) * [1 + H(1)^2 - 1] = H(1)^2 / (8 pi), H(1) = 2.885390
    f = R.hapke(sph(0.0), sph(0.0), N_UP, lunar(w=1.0, b=0.0, c=0.0, B0=0.0, h=0.1, theta_bar=0.0))
    assert f == pytest.approx(2.885390**2 / (8 * np.pi), rel=1e-6)


def test_hapke_lommel_seeliger_limit(rng):
    # dark, isotropic, smooth, no surge: single scattering only, f = w / (4 pi (mu0 + mu))
    wi, wo = upper_dirs(rng, 200), upper_dirs(rng, 200)
    w = 1e-5
    f = R.hapke(wi, wo, N_UP, lunar(w=w, b=0.0, c=0.0, B0=0.0, h=0.1, theta_bar=0.0))
    ls = w / (4 * np.pi * (wi[:, 2] + wo[:, 2]))
    np.testing.assert_allclose(f, ls, rtol=1e-4)


def test_hapke_surge_shape():
    # smooth, dark: f (mu0 + mu) 4 pi / (w p(g)) - 1 = B0 / (1 + tan(g/2)/h); half height at
    # tan(g/2) = h
    B0, h, w = 0.8, 0.05, 1e-6
    g = 2 * np.arctan(np.array([0.0, h, 4 * h]))
    wi = np.broadcast_to(sph(0.5), (3, 3))
    wo = sph(0.5 + g)  # same azimuth plane: phase angle g
    f = R.hapke(wi, wo, N_UP, lunar(w=w, b=0.3, c=0.2, B0=B0, h=h, theta_bar=0.0))
    surge = f * (wi[:, 2] + wo[:, 2]) * 4 * np.pi / (w * R.hapke_phase(np.cos(g), 0.3, 0.2)) - 1
    np.testing.assert_allclose(surge, [B0, B0 / 2, B0 / 5], rtol=1e-4)


def _phase_pair(g_deg, theta=np.pi / 6):
    """wi, wo with i = e = theta and phase angle g (azimuth chosen to give g)."""
    cpsi = (np.cos(np.radians(g_deg)) - np.cos(theta) ** 2) / np.sin(theta) ** 2
    return sph(theta), sph(theta, np.arccos(cpsi))


def test_hapke_opposition_surge_at_zero_phase():
    wi0, wo0 = _phase_pair(0.0)
    wi10, wo10 = _phase_pair(10.0)
    assert np.dot(wi0, wo0) == pytest.approx(1.0)
    assert np.degrees(np.arccos(np.dot(wi10, wo10))) == pytest.approx(10.0)
    with_surge = R.hapke(wi0, wo0, N_UP) / R.hapke(wi10, wo10, N_UP)
    no_surge = R.hapke(wi0, wo0, N_UP, lunar(B0=0.0)) / R.hapke(wi10, wo10, N_UP, lunar(B0=0.0))
    # lunar defaults (B0 = 1, h = 0.07): the single-scattering term gains (1 + B0) / (1 +
    # B0 B(10 deg)) = 2 / 1.555 between 10 deg and 0; the whole BRDF at least 20 %
    assert with_surge > 1.2
    # without the surge the backscatter lobe and roughness shadowing leave only a few percent
    assert no_surge < 1.05


def test_hapke_roughness_is_neutral_at_normal_geometry():
    a = R.hapke(sph(0.0), sph(0.0), N_UP, lunar(theta_bar=0.0))
    b = R.hapke(sph(0.0), sph(0.0), N_UP, lunar(theta_bar=0.5))
    chi = 1 / np.sqrt(1 + np.pi * np.tan(0.5) ** 2)
    # S = 1, only the H functions see mu0e = mue = chi instead of 1
    h1 = R.hapke_h_function(1.0, R.LUNAR_HAPKE.w)
    hc = R.hapke_h_function(chi, R.LUNAR_HAPKE.w)
    p0 = R.hapke_phase(1.0, R.LUNAR_HAPKE.b, R.LUNAR_HAPKE.c) * (1 + R.LUNAR_HAPKE.B0)
    assert b / a == pytest.approx((p0 + hc**2 - 1) / (p0 + h1**2 - 1), rel=1e-9)


def test_hapke_roughness_darkens_grazing_light():
    wi, wo = sph(1.4), sph(0.0)
    assert R.hapke(wi, wo, N_UP, lunar(theta_bar=0.4)) < R.hapke(wi, wo, N_UP, lunar(theta_bar=0.0))


def test_normal_albedo_round_trip():
    f0 = R.hapke(sph(0.0), sph(0.0), N_UP, lunar(w=0.3))
    assert np.pi * f0 == pytest.approx(R.hapke_normal_albedo(0.3), rel=1e-9)
    a = np.array([0.0, 0.05, 0.12, 0.3, 0.6])
    w = R.hapke_w_from_normal_albedo(a)
    assert np.all(np.diff(w) > 0) and w[0] == 0.0
    np.testing.assert_allclose(R.hapke_normal_albedo(w), a, atol=1e-5)
    assert R.hapke_w_from_normal_albedo(5.0) == 1.0


def test_lunar_defaults_documented_values():
    assert np.degrees(R.LUNAR_HAPKE.theta_bar) == pytest.approx(23.657)
    # a lunar-looking normal albedo (order 0.1) for the default w
    assert 0.05 < R.hapke_normal_albedo(R.LUNAR_HAPKE.w) < 0.2


# --- local_angles ---------------------------------------------------------------------------


def test_local_angles_hand_values():
    # theta_i = 60 deg, theta_o = 30 deg, azimuths 0 and 90 / 180 / 0 deg
    c_i, c_o, c_dphi = R.local_angles(
        np.broadcast_to(sph(np.pi / 3), (3, 3)), sph(np.pi / 6, [np.pi / 2, np.pi, 0.0]), N_UP
    )
    np.testing.assert_allclose(c_i, [0.5] * 3)
    np.testing.assert_allclose(c_o, [np.sqrt(3) / 2] * 3)
    np.testing.assert_allclose(c_dphi, [0.0, -1.0, 1.0], atol=1e-12)


def test_local_angles_normalises_and_handles_the_normal_direction():
    # non-unit inputs are normalised (a BRDF of unnormalised vectors would scale with them)
    a = R.local_angles(3.0 * sph(0.7), 0.2 * sph(0.3, 2.0), 5.0 * N_UP)
    b = R.local_angles(sph(0.7), sph(0.3, 2.0), N_UP)
    np.testing.assert_allclose(a, b, rtol=1e-12)
    np.testing.assert_allclose(a[2], np.cos(2.0), rtol=1e-12)
    # a direction along the normal has no azimuth: cos_dphi is defined as 0 there, not NaN
    c_i, c_o, c_dphi = R.local_angles(N_UP, sph(0.5, 1.0), N_UP)
    assert (c_i, c_dphi) == (pytest.approx(1.0), 0.0)
    assert c_o == pytest.approx(np.cos(0.5))


def test_lambert_broadcasts_an_albedo_array():
    albedo = np.array([0.1, 0.5, 0.9])
    f = R.lambert(np.broadcast_to(sph(0.4), (3, 3)), sph([0.2, 0.3, 0.4]), N_UP, albedo)
    np.testing.assert_allclose(f, albedo / np.pi)


# --- lunar-Lambert (McEwen 1991) --------------------------------------------------------------


def test_lunar_lambert_hand_cases():
    rho = 0.4
    normal = R.lunar_lambert(N_UP, N_UP, N_UP, rho, L=1.0)
    assert normal == pytest.approx(rho / np.pi)  # normalised at normal geometry, any L
    assert R.lunar_lambert(N_UP, N_UP, N_UP, rho, L=0.3) == pytest.approx(rho / np.pi)
    # cos i = 0.5, cos o = 1: Lommel-Seeliger 2 / (cos i + cos o) = 4 / 3
    wi = sph(np.pi / 3)
    assert R.lunar_lambert(wi, N_UP, N_UP, rho, L=1.0) == pytest.approx(rho / np.pi * 4 / 3)
    # L = 0.25: 0.75 + 0.25 * 4 / 3 = 13 / 12
    assert R.lunar_lambert(wi, N_UP, N_UP, rho, L=0.25) == pytest.approx(rho / np.pi * 13 / 12)
    wi_g, wo_g = angle_grid()
    np.testing.assert_allclose(
        R.lunar_lambert(wi_g, wo_g, N_UP, rho, L=0.0), R.lambert(wi_g, wo_g, N_UP, rho)
    )
    assert R.lunar_lambert(sph(2.0), N_UP, N_UP, rho) == 0.0  # light below the horizon


def test_lunar_lambert_l_one_is_lommel_seeliger(rng):
    # L = 1: f = A/pi 2/(mu0 + mu); Hapke's single-scattering Lommel-Seeliger law is
    # w/(4 pi (mu0 + mu)) (Hapke 2012, eq. for isotropic single scattering), so the two agree
    # with w = 8 A; checked against the Hapke reference in its dark, smooth, isotropic limit
    wi, wo = upper_dirs(rng, 200), upper_dirs(rng, 200)
    A = 1e-6
    ll = R.lunar_lambert(wi, wo, N_UP, A, L=1.0)
    np.testing.assert_allclose(ll, A / np.pi * 2 / (wi[:, 2] + wo[:, 2]), rtol=1e-12)
    hp = R.hapke(wi, wo, N_UP, lunar(w=8 * A, b=0.0, c=0.0, B0=0.0, h=0.1, theta_bar=0.0))
    np.testing.assert_allclose(ll, hp, rtol=1e-4)


@pytest.mark.parametrize("L", [0.0, 0.4, 1.0])
@pytest.mark.parametrize("theta_i", [0.0, 0.6, 1.2])
def test_lunar_lambert_directional_albedo_closed_form(L, theta_i):
    # int f cos(o) dw_o = A [(1 - L) + 4 L (1 - mu0 ln(1 + 1/mu0))] (integrate
    # 2 pi A/pi [(1 - L) mu + 2 L mu/(mu0 + mu)] over mu in [0, 1]). Normal incidence with
    # L = 1 gives 4 (1 - ln 2) A = 1.227 A: A is a normal albedo, not a hemispherical one, so
    # energy stays below 1 only for A <= 1 / (1 + 3 L) (the grazing limit mu0 -> 0).
    A, mu0 = 0.2, np.cos(theta_i)
    want = A * ((1 - L) + 4 * L * (1 - mu0 * np.log(1 + 1 / mu0)))
    got = directional_albedo(R.lunar_lambert, theta_i, albedo=A, L=L)
    assert got == pytest.approx(want, rel=1e-4)


# --- Oren-Nayar at normal incidence -----------------------------------------------------------


def test_oren_nayar_full_at_normal_incidence_hand_value():
    # theta_i = 0: beta = 0, so tan(beta) = C3 = (2 beta/pi)^2 = 0 and the full model is
    # rho/pi C1 + 0.17 rho^2/pi s2/(s2 + 0.13) whatever the viewer's azimuth; sigma = 0.5:
    # C1 = 0.7844828, inter-reflection factor 0.1118421 (see the hand values above)
    rho = 0.6
    f = R.oren_nayar(np.broadcast_to(N_UP, (4, 3)), sph(0.7, [0.0, 1.0, 2.0, 3.0]), N_UP, rho, 0.5)
    np.testing.assert_allclose(f, (rho * 0.7844828 + rho**2 * 0.1118421) / np.pi, rtol=1e-6)


# --- Hapke's coherent-backscatter opposition effect (Hapke 2002 eq. 32, Hapke 2012) ----------


def test_coherent_backscatter_function_hand_values():
    # B_C(x) = [1 + (1 - e^-x)/x] / [2 (1 + x)^2], x = tan(g/2)/h_C, by hand:
    # x = 0: 1 (the limit (1 - e^-x)/x -> 1); x = 1: (1 + 0.6321206) / 8 = 0.2040151;
    # x = 0.5: (1 + 0.7869387) / 4.5 = 0.3970975; half height at x = 0.3568470 (root found
    # with scipy.optimize.brentq)
    h_C = 0.04
    got = R.hapke_coherent_backscatter(h_C * np.array([0.0, 1e-9, 0.5, 1.0, 0.3568470]), h_C)
    np.testing.assert_allclose(got, [1.0, 1.0, 0.3970975, 0.2040151, 0.5], rtol=2e-7)
    assert np.all(np.diff(R.hapke_coherent_backscatter(np.linspace(0, 1, 50), 0.03)) < 0)


def _closed_form_surge(g, *, w, b, c, B_S0, h_S, B_C0, h_C, theta):
    """f(i = e = theta, g) of the smooth (theta_bar = 0) Hapke model, written out from Hapke
    (2012): w/(4 pi) mu/(mu + mu) [p(g)(1 + B_S0 B_S) + H(mu)^2 - 1] (1 + B_C0 B_C) / mu, with
    p the double Henyey-Greenstein function, B_S = 1/(1 + tan(g/2)/h_S) and
    B_C = [1 + (1 - e^-x)/x] / [2 (1 + x)^2], x = tan(g/2)/h_C (x = 0: 1)."""
    mu, t = np.cos(theta), np.tan(g / 2)
    p = (1 + c) / 2 * (1 - b * b) / (1 - 2 * b * np.cos(g) + b * b) ** 1.5 + (1 - c) / 2 * (
        1 - b * b
    ) / (1 + 2 * b * np.cos(g) + b * b) ** 1.5
    bs = 1 / (1 + t / h_S)
    x = t / h_C
    bc = np.where(x > 0, (1 + (1 - np.exp(-x)) / np.where(x > 0, x, 1)) / (2 * (1 + x) ** 2), 1)
    big_h = R.hapke_h_function(mu, w)  # tested against Chandrasekhar's values above
    return w / (8 * np.pi) * (p * (1 + B_S0 * bs) + big_h**2 - 1) * (1 + B_C0 * bc) / mu


SURGE = dict(w=0.3, b=0.26, c=0.08, B_S0=1.2, h_S=0.06, B_C0=0.8, h_C=0.02, theta=np.pi / 6)
SURGE_PHASES_DEG = [0.0, 0.5, 1.0, 2.0, 5.0]


def test_hapke_opposition_surges_match_the_closed_form_at_zero_and_small_phase():
    k = SURGE
    params = lunar(w=k["w"], b=k["b"], c=k["c"], B0=k["B_S0"], h=k["h_S"], theta_bar=0.0,
                   B_C0=k["B_C0"], h_C=k["h_C"])  # fmt: skip
    for g_deg in SURGE_PHASES_DEG:
        wi, wo = _phase_pair(g_deg, k["theta"])
        g = 2 * np.arcsin(np.linalg.norm(wi - wo) / 2)  # the pair's own g (float rounding)
        assert np.degrees(g) == pytest.approx(g_deg, abs=1e-6)
        want = _closed_form_surge(g, **k)
        assert R.hapke(wi, wo, N_UP, params) == pytest.approx(want, rel=1e-9), g_deg
    # at zero phase both surges are whole: the single-scattering term gains 1 + B_S0 and the
    # whole reflectance 1 + B_C0; without them it is the plain Hapke value
    wi = wo = sph(k["theta"])  # exactly zero phase
    plain = R.hapke(wi, wo, N_UP, dataclasses.replace(params, B0=0.0, B_C0=0.0))
    only_cb = R.hapke(wi, wo, N_UP, dataclasses.replace(params, B0=0.0))
    assert only_cb / plain == pytest.approx(1 + k["B_C0"], rel=1e-12)
    # the coherent peak is narrower than the shadow-hiding one here (h_C < h_S): between 0 and
    # 5 deg it falls from 1 to B_C at x = tan(2.5 deg)/0.02 = 2.183047, by hand
    # (1 + (1 - 0.112698)/2.183047) / (2 * 3.183047^2) = 1.406451 / 20.263578 = 0.069408
    wi5, wo5 = _phase_pair(5.0, k["theta"])
    cb5 = R.hapke(wi5, wo5, N_UP, params) / R.hapke(wi5, wo5, N_UP, replace_cb0(params))
    assert cb5 == pytest.approx(1 + k["B_C0"] * 0.069408, rel=1e-6)


def replace_cb0(params):
    return dataclasses.replace(params, B_C0=0.0)


def test_coherent_backscatter_default_is_off_and_keeps_the_normal_albedo_match():
    assert R.LUNAR_HAPKE.B_C0 == 0.0
    wi, wo = _phase_pair(0.0)
    assert R.hapke(wi, wo, N_UP) == R.hapke(wi, wo, N_UP, lunar(h_C=0.5))  # width unread
    # the normal albedo includes the surge: A_n(B_C0) = (1 + B_C0) A_n(0), and the inversion
    # to w follows it
    assert R.hapke_normal_albedo(0.3, B_C0=0.7) == pytest.approx(1.7 * R.hapke_normal_albedo(0.3))
    f0 = R.hapke(sph(0.0), sph(0.0), N_UP, lunar(w=0.3, B_C0=0.7))
    assert np.pi * f0 == pytest.approx(R.hapke_normal_albedo(0.3, B_C0=0.7), rel=1e-9)
    w = R.hapke_w_from_normal_albedo(0.12, B_C0=0.7)
    assert R.hapke_normal_albedo(w, B_C0=0.7) == pytest.approx(0.12, abs=1e-5)


# --- LROC Empirical (USGS ISIS lronacpho, 2019 coefficients) -----------------------------------

#: (i, e, a) in degrees -> F, the photometric function as ISIS's LROCEmpirical::photometry
#: writes it (algorithm version 2019, phase in degrees), evaluated independently of NumPy and
#: simlunar with Python's decimal module at 40 significant digits (cos by its Taylor series,
#: Decimal.exp and Decimal.sqrt) and rounded to 13 digits. By hand at the normalisation point
#: (30, 0, 30): mu0 = 0.8660254, mu = 1, exponent -1.479654495 - 0.075175 + 0.388941
#: - 1.302352 + 0.556075 + 0.574756 - 0.329939 = -1.667348, exp = 0.188748, times
#: mu0/(mu + mu0) = 0.4641016: F = 0.0875983.
LROC_CASES = {
    (30.0, 0.0, 30.0): 8.759832278886e-02,  # lronacpho's standard geometry
    (0.0, 0.0, 0.0): 2.483358218223e-01,  # normal geometry: the albedo normalisation
    (45.0, 30.0, 15.0): 1.009010562848e-01,
    (60.0, 20.0, 70.0): 3.747956649902e-02,
    (75.0, 45.0, 100.0): 1.533430469771e-02,
    (10.0, 10.0, 0.0): 2.470316392594e-01,  # zero phase
    (85.0, 5.0, 88.0): 5.929693491959e-03,
    (20.0, 40.0, 45.0): 7.461150856274e-02,
}


def _geometry(i_deg, e_deg, a_deg):
    """wi, wo over N_UP with incidence i, emission e and phase angle a (the azimuth difference
    from the spherical law of cosines)."""
    i, e, a = np.radians([i_deg, e_deg, a_deg])
    s = np.sin(i) * np.sin(e)
    cpsi = 1.0 if s == 0 else (np.cos(a) - np.cos(i) * np.cos(e)) / s
    return sph(i), sph(e, np.arccos(np.clip(cpsi, -1.0, 1.0)))


def test_lroc_empirical_reproduces_the_formula_at_hand_computed_geometries():
    for (i, e, a), want in LROC_CASES.items():
        assert R.lroc_empirical_if(i, e, a) == pytest.approx(want, rel=1e-10, abs=0), (i, e, a)
    # lronacpho's correction to the standard geometry is 1 there and F(std) / F elsewhere
    assert R.lroc_empirical_correction(30.0, 0.0, 30.0) == pytest.approx(1.0, rel=1e-15)
    assert R.lroc_empirical_correction(60.0, 20.0, 70.0) == pytest.approx(
        8.759832278886e-02 / 3.747956649902e-02, rel=1e-10
    )


def test_lroc_empirical_brdf_is_the_formula_scaled_to_a_normal_albedo():
    # pi f cos(i) = I/F = A F(i, e, a) / F(0, 0, 0) at every case (the geometry built from
    # the angles: the BRDF reads them back from vectors)
    A, f_normal = 0.17, LROC_CASES[(0.0, 0.0, 0.0)]
    for (i, e, a), want in LROC_CASES.items():
        wi, wo = _geometry(i, e, a)
        assert np.degrees(R.phase_angle(wi, wo)) == pytest.approx(a, abs=1e-9)
        got = np.pi * R.lroc_empirical(wi, wo, N_UP, A) * np.cos(np.radians(i))
        assert got == pytest.approx(A * want / f_normal, rel=1e-9), (i, e, a)
    assert np.pi * R.lroc_empirical(N_UP, N_UP, N_UP, A) == pytest.approx(A, rel=1e-15)
    # light or viewer below the surface: nothing
    assert R.lroc_empirical(sph(1.7), N_UP, N_UP, A) == 0.0
    assert R.lroc_empirical(N_UP, sph(1.7), N_UP, A) == 0.0


def test_lroc_empirical_limb_darkening_is_one_half_at_zero_phase():
    # a = 0 (light at the viewer): mu0 = mu and mu0/(mu + mu0) = 1/2 for every facet, so
    # F = exp(B0 + (B4 + B5) mu + B6 mu^2) / 2 whatever the slope
    b0, _, _, _, b4, b5, b6 = R.LROC_EMPIRICAL_B
    for i in (0.0, 10.0, 35.0, 60.0, 80.0, 89.0):
        mu = np.cos(np.radians(i))
        lommel = R.lroc_empirical_if(i, i, 0.0) / np.exp(b0 + (b4 + b5) * mu + b6 * mu * mu)
        assert lommel == pytest.approx(0.5, rel=1e-14), i
    # ... so a co-located frame sees little shading: from 0 to 40 deg of slope the radiance
    # factor falls by 9.8 % where Lambert's falls by 23.4 % (cos 40 = 0.7660444). By hand:
    # (B4 + B5)(mu - 1) = 1.2197470 * -0.2339556 = -0.2853670, B6 (mu^2 - 1) = -0.4399186 *
    # -0.4131759 = 0.1817638, exp(-0.1036032) = 0.9015833
    ratio = R.lroc_empirical_if(40.0, 40.0, 0.0) / R.lroc_empirical_if(0.0, 0.0, 0.0)
    assert ratio == pytest.approx(0.9015833, rel=1e-6)


def test_lroc_empirical_is_not_reciprocal_and_conserves_energy():
    wi, wo = _geometry(60.0, 20.0, 70.0)
    # B4 != B5: swapping light and viewer changes the value (why the plugin reads the mode)
    assert R.lroc_empirical(wi, wo, N_UP) / R.lroc_empirical(wo, wi, N_UP) == pytest.approx(
        np.exp((0.556075496 - 0.663671460) * (np.cos(np.radians(20)) - np.cos(np.radians(60)))
               + -0.439918609 * (np.cos(np.radians(60)) ** 2 - np.cos(np.radians(20)) ** 2))
    )  # fmt: skip
    for theta_i in (0.0, 0.8, 1.4, 1.5707):
        albedo = directional_albedo(R.lroc_empirical, theta_i, albedo=1.0)
        assert 0.3 < albedo < 0.47, theta_i
