"""The NumPy reference Hapke BRDF (simlunar/render/reference_hapke.py): its phase and H
functions, opposition surges and roughness against hand-computed and closed-form values, its
energy, and the normal albedo that sets ``w``. Pure NumPy: nothing here needs Mitsuba."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simlunar.render import reference_hapke as H
from tests.render.test_reference import N_UP, directional_albedo, lunar, sph, upper_dirs

# --- energy ---------------------------------------------------------------------------------


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
        a = directional_albedo(H.hapke, theta_i, params=lunar(**kw))
        assert 0.0 < a <= 1.0, (theta_i, a)


# --- parts and hand values ------------------------------------------------------------------


def test_hg_phase_function_is_normalised():
    # mean of p over the sphere is 1 for any (b, c)
    mu = np.linspace(-1, 1, 200001)
    for b, c in [(0.26, 0.08), (0.6, -0.5), (0.1, 1.0)]:
        p = H.hapke_phase(mu, b, c)
        assert np.trapezoid(p, mu) / 2 == pytest.approx(1.0, rel=1e-5)
    # c = 1: pure backscatter lobe peaks at g = 0 with (1 + b)/(1 - b)^2
    assert H.hapke_phase(1.0, 0.5, 1.0) == pytest.approx(1.5 / 0.25)


def test_h_function_against_chandrasekhar():
    # Chandrasekhar (1960) conservative isotropic scattering: H(1) = 2.90781; Hapke's (2002)
    # approximation claims ~1 %. By hand: r0 = 1, H(1) = 1 / (0.5 ln 2) = 2.885390
    assert H.hapke_h_function(1.0, 1.0) == pytest.approx(1 / (0.5 * np.log(2)), rel=1e-12)
    assert H.hapke_h_function(1.0, 1.0) == pytest.approx(2.90781, rel=0.01)
    assert H.hapke_h_function(0.5, 0.0) == 1.0  # no scattering, no multiple scattering


def test_hapke_hand_value_at_normal_geometry():
    # theta_bar = 0, isotropic particles (b = 0), no surge, w = 1, i = e = g = 0:
    # f = w/(4 pi) * 1/(1 + 1) * [1 + H(1)^2 - 1] = H(1)^2 / (8 pi), H(1) = 2.885390
    f = H.hapke(sph(0.0), sph(0.0), N_UP, lunar(w=1.0, b=0.0, c=0.0, B0=0.0, h=0.1, theta_bar=0.0))
    assert f == pytest.approx(2.885390**2 / (8 * np.pi), rel=1e-6)


def test_hapke_lommel_seeliger_limit(rng):
    # dark, isotropic, smooth, no surge: single scattering only, f = w / (4 pi (mu0 + mu))
    wi, wo = upper_dirs(rng, 200), upper_dirs(rng, 200)
    w = 1e-5
    f = H.hapke(wi, wo, N_UP, lunar(w=w, b=0.0, c=0.0, B0=0.0, h=0.1, theta_bar=0.0))
    ls = w / (4 * np.pi * (wi[:, 2] + wo[:, 2]))
    np.testing.assert_allclose(f, ls, rtol=1e-4)


def test_hapke_surge_shape():
    # smooth, dark: f (mu0 + mu) 4 pi / (w p(g)) - 1 = B0 / (1 + tan(g/2)/h); half height at
    # tan(g/2) = h
    B0, h, w = 0.8, 0.05, 1e-6
    g = 2 * np.arctan(np.array([0.0, h, 4 * h]))
    wi = np.broadcast_to(sph(0.5), (3, 3))
    wo = sph(0.5 + g)  # same azimuth plane: phase angle g
    f = H.hapke(wi, wo, N_UP, lunar(w=w, b=0.3, c=0.2, B0=B0, h=h, theta_bar=0.0))
    surge = f * (wi[:, 2] + wo[:, 2]) * 4 * np.pi / (w * H.hapke_phase(np.cos(g), 0.3, 0.2)) - 1
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
    with_surge = H.hapke(wi0, wo0, N_UP) / H.hapke(wi10, wo10, N_UP)
    no_surge = H.hapke(wi0, wo0, N_UP, lunar(B0=0.0)) / H.hapke(wi10, wo10, N_UP, lunar(B0=0.0))
    # lunar defaults (B0 = 1, h = 0.07): the single-scattering term gains (1 + B0) / (1 +
    # B0 B(10 deg)) = 2 / 1.555 between 10 deg and 0; the whole BRDF at least 20 %
    assert with_surge > 1.2
    # without the surge the backscatter lobe and roughness shadowing leave only a few percent
    assert no_surge < 1.05


def test_hapke_roughness_is_neutral_at_normal_geometry():
    a = H.hapke(sph(0.0), sph(0.0), N_UP, lunar(theta_bar=0.0))
    b = H.hapke(sph(0.0), sph(0.0), N_UP, lunar(theta_bar=0.5))
    chi = 1 / np.sqrt(1 + np.pi * np.tan(0.5) ** 2)
    # S = 1, only the H functions see mu0e = mue = chi instead of 1
    h1 = H.hapke_h_function(1.0, H.LUNAR_HAPKE.w)
    hc = H.hapke_h_function(chi, H.LUNAR_HAPKE.w)
    p0 = H.hapke_phase(1.0, H.LUNAR_HAPKE.b, H.LUNAR_HAPKE.c) * (1 + H.LUNAR_HAPKE.B0)
    assert b / a == pytest.approx((p0 + hc**2 - 1) / (p0 + h1**2 - 1), rel=1e-9)


def test_hapke_roughness_darkens_grazing_light():
    wi, wo = sph(1.4), sph(0.0)
    assert H.hapke(wi, wo, N_UP, lunar(theta_bar=0.4)) < H.hapke(wi, wo, N_UP, lunar(theta_bar=0.0))


def test_normal_albedo_round_trip():
    f0 = H.hapke(sph(0.0), sph(0.0), N_UP, lunar(w=0.3))
    assert np.pi * f0 == pytest.approx(H.hapke_normal_albedo(0.3), rel=1e-9)
    a = np.array([0.0, 0.05, 0.12, 0.3, 0.6])
    w = H.hapke_w_from_normal_albedo(a)
    assert np.all(np.diff(w) > 0) and w[0] == 0.0
    np.testing.assert_allclose(H.hapke_normal_albedo(w), a, atol=1e-5)
    assert H.hapke_w_from_normal_albedo(5.0) == 1.0


def test_lunar_defaults_documented_values():
    assert np.degrees(H.LUNAR_HAPKE.theta_bar) == pytest.approx(23.657)
    # a lunar-looking normal albedo (order 0.1) for the default w
    assert 0.05 < H.hapke_normal_albedo(H.LUNAR_HAPKE.w) < 0.2


# --- Hapke's coherent-backscatter opposition effect (Hapke 2002 eq. 32, Hapke 2012) ----------


def test_coherent_backscatter_function_hand_values():
    # B_C(x) = [1 + (1 - e^-x)/x] / [2 (1 + x)^2], x = tan(g/2)/h_C, by hand:
    # x = 0: 1 (the limit (1 - e^-x)/x -> 1); x = 1: (1 + 0.6321206) / 8 = 0.2040151;
    # x = 0.5: (1 + 0.7869387) / 4.5 = 0.3970975; half height at x = 0.3568470 (root found
    # with scipy.optimize.brentq)
    h_C = 0.04
    got = H.hapke_coherent_backscatter(h_C * np.array([0.0, 1e-9, 0.5, 1.0, 0.3568470]), h_C)
    np.testing.assert_allclose(got, [1.0, 1.0, 0.3970975, 0.2040151, 0.5], rtol=2e-7)
    assert np.all(np.diff(H.hapke_coherent_backscatter(np.linspace(0, 1, 50), 0.03)) < 0)


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
    big_h = H.hapke_h_function(mu, w)  # tested against Chandrasekhar's values above
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
        assert H.hapke(wi, wo, N_UP, params) == pytest.approx(want, rel=1e-9), g_deg
    # at zero phase both surges are whole: the single-scattering term gains 1 + B_S0 and the
    # whole reflectance 1 + B_C0; without them it is the plain Hapke value
    wi = wo = sph(k["theta"])  # exactly zero phase
    plain = H.hapke(wi, wo, N_UP, dataclasses.replace(params, B0=0.0, B_C0=0.0))
    only_cb = H.hapke(wi, wo, N_UP, dataclasses.replace(params, B0=0.0))
    assert only_cb / plain == pytest.approx(1 + k["B_C0"], rel=1e-12)
    # the coherent peak is narrower than the shadow-hiding one here (h_C < h_S): between 0 and
    # 5 deg it falls from 1 to B_C at x = tan(2.5 deg)/0.02 = 2.183047, by hand
    # (1 + (1 - 0.112698)/2.183047) / (2 * 3.183047^2) = 1.406451 / 20.263578 = 0.069408
    wi5, wo5 = _phase_pair(5.0, k["theta"])
    cb5 = H.hapke(wi5, wo5, N_UP, params) / H.hapke(wi5, wo5, N_UP, replace_cb0(params))
    assert cb5 == pytest.approx(1 + k["B_C0"] * 0.069408, rel=1e-6)


def replace_cb0(params):
    return dataclasses.replace(params, B_C0=0.0)


def test_coherent_backscatter_default_is_off_and_keeps_the_normal_albedo_match():
    assert H.LUNAR_HAPKE.B_C0 == 0.0
    wi, wo = _phase_pair(0.0)
    assert H.hapke(wi, wo, N_UP) == H.hapke(wi, wo, N_UP, lunar(h_C=0.5))  # width unread
    # the normal albedo includes the surge: A_n(B_C0) = (1 + B_C0) A_n(0), and the inversion
    # to w follows it
    assert H.hapke_normal_albedo(0.3, B_C0=0.7) == pytest.approx(1.7 * H.hapke_normal_albedo(0.3))
    f0 = H.hapke(sph(0.0), sph(0.0), N_UP, lunar(w=0.3, B_C0=0.7))
    assert np.pi * f0 == pytest.approx(H.hapke_normal_albedo(0.3, B_C0=0.7), rel=1e-9)
    w = H.hapke_w_from_normal_albedo(0.12, lunar(B_C0=0.7))
    assert H.hapke_normal_albedo(w, B_C0=0.7) == pytest.approx(0.12, abs=1e-5)
