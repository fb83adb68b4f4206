"""The NumPy reference BRDFs (simlunar/render/reference.py): limits, symmetries, energy and
hand-computed values of Lambert, lunar-Lambert, Oren-Nayar and LROC Empirical, Hapke's
reciprocity beside them (its own values: test_reference_hapke.py), and the geometry helper
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
