"""The LROC Empirical BSDF: its spec and YAML block, and its Mitsuba plugin against the NumPy
reference (eval in both transport modes, zero phase, sampling and pdf, a rendered tilted
plane); the reference itself is tested in tests/render/test_reference.py."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.render import reference as R
from simlunar.render.bsdfs import bsdf_dict
from simlunar.render.materials import BSDFS, make_bsdf
from simlunar.render.plugins.lroc_empirical import COEFFICIENTS, LROCEmpiricalBSDF
from tests.render.test_bsdfs import _sample, angle_grid, eval_plugin, sph

N_UP = np.array([0.0, 0.0, 1.0])


def test_spec_registry_and_errors():
    assert BSDFS["lroc_empirical"].target is LROCEmpiricalBSDF
    assert BSDFS["lroc_empirical"].meta["label"] == "LROC Empirical"
    spec = make_bsdf("lroc_empirical")
    assert spec.coefficients == R.LROC_EMPIRICAL_B
    d = bsdf_dict(spec, 0.3)
    assert d == {"type": "lroc_empirical", "reflectance": 0.3,
                 **dict(zip(COEFFICIENTS, R.LROC_EMPIRICAL_B[1:], strict=True))}  # fmt: skip
    assert make_bsdf("lroc_empirical", B3=-0.3).coefficients[3] == -0.3
    with pytest.raises(ValueError, match=r"B3 must be a finite number, got nan"):
        make_bsdf("lroc_empirical", B3=float("nan"))
    with pytest.raises(ValueError, match=r"unknown parameter\(s\) B0 for BSDF 'lroc_empirical'"):
        make_bsdf("lroc_empirical", B0=-1.0)  # B0 cancels: not a parameter
    with pytest.raises(ValueError, match=r"unknown BSDF 'lroc_empiric'.*'lroc_empirical'"):
        make_bsdf("lroc_empiric")


def test_yaml_block_is_derived_from_the_spec():
    from pydantic import TypeAdapter, ValidationError

    from simlunar.config import translate
    from simlunar.config.render import BsdfCfg

    ta = TypeAdapter(BsdfCfg)
    assert translate.bsdf(ta.validate_python({"kind": "lroc_empirical"})) == LROCEmpiricalBSDF()
    got = translate.bsdf(ta.validate_python({"kind": "lroc_empirical", "B5": 0.7}))
    assert got == LROCEmpiricalBSDF(B5=0.7)
    with pytest.raises(ValidationError, match="Extra inputs"):
        ta.validate_python({"kind": "lroc_empirical", "b5": 0.7})


def _reference(wi_light, wo_view, albedo, B=R.LROC_EMPIRICAL_B):
    """Reference f * cos(theta_o) of Mitsuba's ``eval`` (o: its ``wo``) for light and viewer."""
    return R.lroc_empirical(wi_light, wo_view, N_UP, albedo, B=B)


@pytest.mark.parametrize("albedo", [0.12, 0.6])
def test_plugin_eval_matches_reference_in_both_transport_modes(mi, albedo):
    bsdf = mi.load_dict(bsdf_dict(make_bsdf("lroc_empirical"), albedo))
    wi, wo = angle_grid()  # si.wi, wo of Mitsuba's eval
    # radiance mode (path tracing): wo is the direction to the light, si.wi to the viewer
    got = eval_plugin(mi, bsdf, wi, wo)
    want = _reference(wo, wi, albedo) * wo[:, 2]
    np.testing.assert_allclose(got, np.repeat(want[:, None], 3, 1), rtol=1e-4)
    # importance mode (light tracing): si.wi came from the light, wo goes to the viewer
    imp = eval_plugin(mi, bsdf, wi, wo, ctx=mi.BSDFContext(mi.TransportMode.Importance))
    np.testing.assert_allclose(imp[:, 0], _reference(wi, wo, albedo) * wo[:, 2], rtol=1e-4)
    # the fit is not reciprocal, so the two modes differ off the diagonal i = e
    off = np.abs(wi[:, 2] - wo[:, 2]) > 0.1
    assert np.all(np.abs(imp[off, 0] / got[off, 0] - 1) > 1e-3)
    below = eval_plugin(mi, bsdf, sph([0.3, 1.9]), sph([2.0, 0.5]))[:, 0]
    assert np.all(below == 0)


def test_plugin_normal_albedo_and_zero_phase(mi):
    albedo = 0.21
    bsdf = mi.load_dict(bsdf_dict(make_bsdf("lroc_empirical"), albedo))
    # seen and lit from straight above: pi f = the normal albedo
    v = eval_plugin(mi, bsdf, sph(np.array([0.0])), sph(np.array([0.0])))
    assert np.pi * v[0, 0] == pytest.approx(albedo, rel=1e-6)
    # zero phase (wi = wo, a light at the camera): mu0/(mu + mu0) = 1/2 on every facet, so
    # pi f mu0 / A = exp((B4 + B5)(mu - 1) + B6 (mu^2 - 1)) (2 / (2 mu) times mu0 = mu)
    _, _, _, _, b4, b5, b6 = R.LROC_EMPIRICAL_B
    theta = np.radians([5.0, 20.0, 40.0, 60.0, 80.0])
    d = sph(theta, 0.7)
    got = np.pi * eval_plugin(mi, bsdf, d, d)[:, 0] / albedo
    mu = np.cos(theta)
    np.testing.assert_allclose(got, np.exp((b4 + b5) * (mu - 1) + b6 * (mu * mu - 1)), rtol=1e-5)


def test_traverse_changes_a_coefficient_and_checks_it(mi):
    bsdf = mi.load_dict({"type": "lroc_empirical", "reflectance": 0.3})
    wi, wo = angle_grid()
    params = mi.traverse(bsdf)
    assert {"B1", "B6"} <= set(params.keys())
    params["B3"] = -0.1
    params.update()
    B = list(R.LROC_EMPIRICAL_B)
    B[3] = -0.1
    got = eval_plugin(mi, bsdf, wi, wo)[:, 0]
    np.testing.assert_allclose(got, _reference(wo, wi, 0.3, B=B) * wo[:, 2], rtol=1e-4)
    with pytest.raises((ValueError, RuntimeError), match=r"B2 must be a finite number, got inf"):
        mi.load_dict({"type": "lroc_empirical", "B2": float("inf")})


def _swapped(wi, wo, n, albedo):
    """The reference with light and viewer swapped (Mitsuba's radiance-mode roles)."""
    return R.lroc_empirical(wo, wi, n, albedo)


@pytest.mark.parametrize("mode", ["Radiance", "Importance"])
def test_sample_weight_is_eval_over_pdf(mi, mode):
    from tests.render.test_reference import directional_albedo

    ctx = mi.BSDFContext(getattr(mi.TransportMode, mode))
    bsdf = mi.load_dict(bsdf_dict(make_bsdf("lroc_empirical"), 0.5))
    for theta_i in (0.2, 1.0, 1.45):
        wo, pdf, weight = _sample(mi, bsdf, theta_i, n=100_000, ctx=ctx)
        ok = pdf > 0
        assert ok.mean() > 0.999
        np.testing.assert_allclose(pdf[ok], wo[ok, 2] / np.pi, rtol=1e-5)  # cosine-weighted
        ev = eval_plugin(mi, bsdf, np.broadcast_to(sph(theta_i), wo.shape), wo, ctx=ctx)
        np.testing.assert_allclose(weight[ok], ev[ok] / pdf[ok, None], rtol=1e-4, atol=1e-6)
        # the mean weight estimates the integral of f cos over the sampled hemisphere: in
        # radiance mode over the light's directions (si.wi the viewer), in importance mode
        # over the viewer's; the reference's quadrature agrees within 4 standard errors
        ref = _swapped if mode == "Radiance" else R.lroc_empirical
        quad = directional_albedo(ref, theta_i, albedo=0.5)
        sem = weight[:, 0].std() / np.sqrt(len(weight))
        assert abs(weight[:, 0].mean() - quad) < 4 * sem, (mode, theta_i)


def test_chi2_sampling(mi):
    chi2 = mi.chi2
    d = bsdf_dict(make_bsdf("lroc_empirical"), 0.5)
    sample_func, pdf_func = chi2.BSDFAdapter("lroc_empirical", d, wi=sph(0.7).tolist())
    test = chi2.ChiSquareTest(
        domain=chi2.SphericalDomain(),
        sample_func=sample_func,
        pdf_func=pdf_func,
        sample_dim=3,
        sample_count=200_000,
        res=51,
        seed=3,
    )
    assert test.run(0.01, quiet=True), test.messages


def _tilted_plane_scene(mi, spec, albedo, wl, integrator, camera):
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": integrator,
            "plane": {
                "type": "rectangle",
                "bsdf": bsdf_dict(spec, albedo),
                # the rectangle's normal +z rotated 25 deg about x: (0, -sin 25, cos 25)
                "to_world": mi.ScalarTransform4f().rotate([1, 0, 0], 25.0).scale([10, 10, 1]),
            },
            "sun": {"type": "directional", "direction": (-wl).tolist(), "irradiance": 2.0},
            "cam": {
                **camera,
                "film": {"type": "hdrfilm", "width": 8, "height": 8, "rfilter": {"type": "box"}},
                "sampler": {"type": "independent", "sample_count": 4},
            },
        }
    )


TILT_N = np.array([0.0, -np.sin(np.radians(25.0)), np.cos(np.radians(25.0))])
#: the sun's direction (towards it): 55 deg from the zenith, azimuth 200 deg; the camera looks
#: straight down, so on the tilted plane i = 50.3 deg, e = 25 deg, a = 55 deg
SUN = sph(np.radians(55.0), np.radians(200.0))
UP = np.array([0.0, 0.0, 1.0])


@pytest.mark.render
def test_rendered_tilted_plane_equals_the_reference(mi):
    """A plane tilted 25 deg under a directional light seen by an orthographic camera from
    straight above, direct illumination: every pixel's radiance is exactly E f(wi, wo, n)
    cos(i) (delta light and camera: no sampling noise)."""
    camera = {
        "type": "orthographic",
        "to_world": mi.ScalarTransform4f().look_at(
            origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]
        ),
    }
    i = np.degrees(np.arccos(TILT_N @ SUN))
    assert i == pytest.approx(50.34, abs=0.01)
    for albedo in (0.12, 0.3):
        scene = _tilted_plane_scene(
            mi, make_bsdf("lroc_empirical"), albedo, SUN, {"type": "direct"}, camera
        )
        img = np.array(mi.render(scene, spp=4))
        want = 2.0 * R.lroc_empirical(SUN, UP, TILT_N, albedo) * (TILT_N @ SUN)
        np.testing.assert_allclose(img, want, rtol=1e-3)
        # light and viewer swapped would be 14 % darker: the test sees the roles
        swapped = 2.0 * R.lroc_empirical(UP, SUN, TILT_N, albedo) * (TILT_N @ SUN)
        assert abs(swapped / want - 1) > 0.1


@pytest.mark.render
@pytest.mark.slow
def test_light_traced_tilted_plane_agrees_with_the_reference(mi):
    """The same plane light-traced (``ptracer``: importance mode, the plugin swaps the roles):
    the image mean agrees with the reference within its Monte Carlo error (measured 0.2 % at
    4096 spp with 8 x 8 pixels; 2 % allowed, the swapped roles are 14 % off)."""
    camera = {
        "type": "perspective",
        "fov": 1.0,  # 100 m away: the view direction varies by 0.5 deg across the image
        "to_world": mi.ScalarTransform4f().look_at(
            origin=[0, 0, 100], target=[0, 0, 0], up=[0, 1, 0]
        ),
    }
    scene = _tilted_plane_scene(
        mi,
        make_bsdf("lroc_empirical"),
        0.3,
        SUN,
        {"type": "ptracer", "max_depth": 2},
        camera,
    )
    img = np.array(mi.render(scene, spp=8192, seed=1))
    want = 2.0 * R.lroc_empirical(SUN, UP, TILT_N, 0.3) * (TILT_N @ SUN)
    assert img[..., 0].mean() == pytest.approx(want, rel=0.02)
