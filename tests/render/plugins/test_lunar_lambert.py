"""The lunar-Lambert BSDF: its spec and YAML block, and its Mitsuba plugin against the NumPy
reference (eval, reciprocity, sampling and pdf); the reference itself is tested in
tests/render/test_reference.py."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.render import reference as R
from simlunar.render.bsdfs import bsdf_dict
from simlunar.render.materials import BSDFS, make_bsdf
from simlunar.render.plugins.lunar_lambert import LunarLambertBSDF
from tests.render.test_bsdfs import _sample, angle_grid, eval_plugin, sph

N_UP = np.array([0.0, 0.0, 1.0])


def test_spec_registry_and_errors():
    assert BSDFS["lunar_lambert"].target is LunarLambertBSDF
    assert make_bsdf("lunar_lambert", L=0.2) == LunarLambertBSDF(0.2)
    assert bsdf_dict(make_bsdf("lunar_lambert", L=0.2), 0.3) == {
        "type": "lunar_lambert",
        "reflectance": 0.3,
        "L": 0.2,
    }
    with pytest.raises(ValueError, match=r"L must be <= 1, got 1\.5"):
        make_bsdf("lunar_lambert", L=1.5)
    with pytest.raises(ValueError, match=r"unknown BSDF 'lunar_lambart'.*'lunar_lambert'"):
        make_bsdf("lunar_lambart")


def test_yaml_block_is_derived_from_the_spec():
    from pydantic import TypeAdapter, ValidationError

    from simlunar.config import translate
    from simlunar.config.render import BsdfCfg

    ta = TypeAdapter(BsdfCfg)
    assert translate.bsdf(ta.validate_python({"kind": "lunar_lambert", "L": 0.25})) == (
        LunarLambertBSDF(0.25)
    )
    assert translate.bsdf(ta.validate_python({"kind": "lunar_lambert"})) == LunarLambertBSDF()
    with pytest.raises(ValidationError, match="less than or equal to 1"):
        ta.validate_python({"kind": "lunar_lambert", "L": 2})
    with pytest.raises(ValidationError, match="Extra inputs"):
        ta.validate_python({"kind": "lunar_lambert", "l": 0.5})


@pytest.mark.parametrize(("L", "albedo"), [(0.0, 0.7), (0.5, 0.12), (1.0, 0.9)])
def test_plugin_eval_matches_reference(mi, L, albedo):
    bsdf = mi.load_dict(bsdf_dict(make_bsdf("lunar_lambert", L=L), albedo))
    wi, wo = angle_grid()
    got = eval_plugin(mi, bsdf, wi, wo)
    want = R.lunar_lambert(wi, wo, N_UP, albedo, L=L) * wo[:, 2]
    np.testing.assert_allclose(got, np.repeat(want[:, None], 3, 1), rtol=5e-3)  # 0.5 %
    # reciprocity f(wi, wo) = f(wo, wi)
    back = eval_plugin(mi, bsdf, wo, wi)[:, 0] / wi[:, 2]
    np.testing.assert_allclose(got[:, 0] / wo[:, 2], back, rtol=1e-5)
    below = eval_plugin(mi, bsdf, sph([0.3, 1.9]), sph([2.0, 0.5]))[:, 0]
    assert np.all(below == 0)


def test_plugin_at_l_zero_is_the_builtin_diffuse(mi):
    wi, wo = angle_grid()
    ours = eval_plugin(mi, mi.load_dict(bsdf_dict(make_bsdf("lunar_lambert", L=0.0), 0.6)), wi, wo)
    builtin = eval_plugin(mi, mi.load_dict(bsdf_dict(make_bsdf("lambert"), 0.6)), wi, wo)
    np.testing.assert_allclose(ours, builtin, rtol=1e-6, atol=1e-8)


def test_sample_weight_is_eval_over_pdf(mi):
    bsdf = mi.load_dict(bsdf_dict(make_bsdf("lunar_lambert", L=0.8), 0.5))
    for theta_i in (0.2, 1.0, 1.45):
        wo, pdf, weight = _sample(mi, bsdf, theta_i, n=50_000)
        ok = pdf > 0
        assert ok.mean() > 0.999
        np.testing.assert_allclose(pdf[ok], wo[ok, 2] / np.pi, rtol=1e-5)
        ev = eval_plugin(mi, bsdf, np.broadcast_to(sph(theta_i), wo.shape), wo)
        np.testing.assert_allclose(weight[ok], ev[ok] / pdf[ok, None], rtol=1e-4, atol=1e-6)


def test_chi2_sampling(mi):
    chi2 = mi.chi2
    d = {"type": "lunar_lambert", "reflectance": 0.5, "L": 0.7}
    sample_func, pdf_func = chi2.BSDFAdapter("lunar_lambert", d, wi=sph(0.7).tolist())
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


def test_traverse_changes_l_and_checks_it(mi):
    bsdf = mi.load_dict({"type": "lunar_lambert", "reflectance": 0.5, "L": 0.0})
    wi, wo = angle_grid()
    params = mi.traverse(bsdf)
    params["L"] = 1.0
    params.update()
    got = eval_plugin(mi, bsdf, wi, wo)[:, 0]
    np.testing.assert_allclose(got, R.lunar_lambert(wi, wo, N_UP, 0.5, L=1.0) * wo[:, 2], rtol=5e-3)
    with pytest.raises((ValueError, RuntimeError), match=r"L must be in \[0, 1\], got 1\.2"):
        mi.load_dict({"type": "lunar_lambert", "L": 1.2})
