"""Mitsuba plugins ``oren_nayar`` and ``hapke`` against the NumPy references."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from simlunar.render import reference as R
from simlunar.render.bsdfs import HAPKE_TABLE_SIZE, bsdf_dict
from simlunar.render.materials import make_bsdf

N_UP = np.array([0.0, 0.0, 1.0])


def sph(theta, phi=0.0):
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)


def angle_grid():
    """(wi, wo) pairs over theta_i, theta_o in 5..85 deg and azimuth differences 0..180."""
    t = np.radians(np.arange(5, 90, 10))
    p = np.radians(np.arange(0, 181, 30))
    ti, to, dp = (a.ravel() for a in np.meshgrid(t, t, p, indexing="ij"))
    return sph(ti, 0.3), sph(to, 0.3 + dp)


def eval_plugin(mi, bsdf, wi, wo, uv=None, ctx=None):
    """bsdf.eval in the local frame (z = normal) -> (n, 3) numpy (f * cos_o); ``ctx`` the
    BSDF context (default: radiance transport)."""
    import drjit as dr

    n = len(wi)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T, dtype=np.float32))
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.n = mi.Normal3f(0, 0, 1)
    if uv is not None:
        si.uv = mi.Point2f(np.ascontiguousarray(uv.T, dtype=np.float32))
    wo_m = mi.Vector3f(np.ascontiguousarray(wo.T, dtype=np.float32))
    ctx = mi.BSDFContext() if ctx is None else ctx
    return np.array(bsdf.eval(ctx, si, wo_m)).T.astype(np.float64)


#: float32 unit roundoff (2^-23 = 1.19e-7): the relative size of one ulp
F32_EPS = float(np.finfo(np.float32).eps)


def assert_within_ulps(got, want, n_ulp):
    """``|got - want| <= n_ulp * eps32 * |want|`` elementwise (so zeros must match exactly).

    For results that two code paths compute with the same float32 formulas but that a JIT
    backend may round differently (CUDA contracts ``a * b + c`` into FMAs and constant-folds
    opaque scalars differently from per-lane values: measured 1 ulp apart on an H100).
    """
    got, want = np.asarray(got, np.float64), np.asarray(want, np.float64)
    bad = np.abs(got - want) > n_ulp * F32_EPS * np.abs(want)
    assert not bad.any(), (
        f"{bad.sum()} of {bad.size} values differ by more than {n_ulp} ulp; worst relative "
        f"difference {np.max(np.abs(got - want)[bad] / np.abs(want)[bad]):.3g}"
    )


def reference_for(d, wi, wo, albedo):
    """Reference f * cos_o for a plugin dict."""
    cos_o = wo[..., 2]
    if d["type"] == "oren_nayar":
        f = R.oren_nayar(wi, wo, N_UP, albedo, d["sigma"], d.get("model", "full"))
    elif d["type"] == "diffuse":
        f = R.lambert(wi, wo, N_UP, albedo)
    else:
        p = {k: d[k] for k in ("b", "c", "B0", "h", "theta_bar")}
        shape = replace(R.LUNAR_HAPKE, **p)
        w = albedo if d["albedo_mode"] == "w" else R.hapke_w_from_normal_albedo(albedo, shape)
        f = R.hapke(wi, wo, N_UP, R.HapkeParams(w=w, **p))
    return f * cos_o


SPECS = [
    (make_bsdf("oren_nayar", sigma=0.0), 0.7),
    (make_bsdf("oren_nayar", sigma=0.3), 0.7),
    (make_bsdf("oren_nayar", sigma=1.0), 0.9),
    (make_bsdf("oren_nayar", sigma=1.0, model="qualitative"), 0.9),
    (make_bsdf("hapke"), 0.12),
    (make_bsdf("hapke", B0=0.0, theta_bar=0.0, b=0.5, c=-0.4), 0.3),
    (make_bsdf("hapke", w=0.6, theta_bar=0.4), 0.0),
]


@pytest.mark.parametrize(("spec", "albedo"), SPECS)
def test_plugin_eval_matches_reference(mi, spec, albedo):
    d = bsdf_dict(spec, albedo)
    bsdf = mi.load_dict(d)
    wi, wo = angle_grid()
    got = eval_plugin(mi, bsdf, wi, wo)
    want = reference_for(d, wi, wo, albedo if spec.name != "hapke" or spec.w is None else spec.w)
    assert got.shape == (len(wi), 3)
    np.testing.assert_allclose(got, np.repeat(want[:, None], 3, 1), rtol=2e-4, atol=1e-7)


def test_oren_nayar_sigma_zero_equals_builtin_diffuse(mi):
    wi, wo = angle_grid()
    ours = eval_plugin(mi, mi.load_dict(bsdf_dict(make_bsdf("oren_nayar", sigma=0.0), 0.6)), wi, wo)
    builtin = eval_plugin(mi, mi.load_dict(bsdf_dict(make_bsdf("lambert"), 0.6)), wi, wo)
    np.testing.assert_allclose(ours, builtin, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(builtin[:, 0], 0.6 / np.pi * wo[:, 2], rtol=1e-6)


@pytest.mark.parametrize(("spec", "albedo"), SPECS)
def test_plugin_reciprocity(mi, spec, albedo):
    bsdf = mi.load_dict(bsdf_dict(spec, albedo))
    wi, wo = angle_grid()
    a = eval_plugin(mi, bsdf, wi, wo)[:, 0] / wo[:, 2]
    b = eval_plugin(mi, bsdf, wo, wi)[:, 0] / wi[:, 2]
    np.testing.assert_allclose(a, b, rtol=5e-4, atol=1e-7)


def test_plugin_zero_below_horizon(mi):
    for spec, albedo in SPECS[1:5]:
        bsdf = mi.load_dict(bsdf_dict(spec, albedo))
        wi = sph([0.3, 1.9, 0.3])
        wo = sph([0.5, 0.5, 2.0])
        v = eval_plugin(mi, bsdf, wi, wo)[:, 0]
        assert v[0] > 0 and v[1] == 0 and v[2] == 0


def _sample(mi, bsdf, theta_i, n=200_000, seed=1, ctx=None):
    import drjit as dr

    rng = np.random.default_rng(seed)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(*(float(x) for x in sph(theta_i)))
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    u = rng.random((3, n)).astype(np.float32)
    ctx = mi.BSDFContext() if ctx is None else ctx
    bs, weight = bsdf.sample(ctx, si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
    return np.array(bs.wo).T, np.array(bs.pdf), np.array(weight).T


@pytest.mark.parametrize(("spec", "albedo"), [SPECS[2], SPECS[3], SPECS[4], SPECS[6]])
def test_sample_weight_is_eval_over_pdf_and_albedo_at_most_one(mi, spec, albedo):
    bsdf = mi.load_dict(bsdf_dict(spec, albedo if spec.name != "hapke" or spec.w is None else 0))
    for theta_i in (0.2, 1.0, 1.45):
        wo, pdf, weight = _sample(mi, bsdf, theta_i, n=100_000)
        ok = pdf > 0
        assert ok.mean() > 0.999
        np.testing.assert_allclose(pdf[ok], wo[ok, 2] / np.pi, rtol=1e-5)
        ev = eval_plugin(mi, bsdf, np.broadcast_to(sph(theta_i), wo.shape), wo)
        np.testing.assert_allclose(weight[ok], ev[ok] / pdf[ok, None], rtol=1e-4, atol=1e-6)
        # the mean weight estimates the directional albedo; 100k samples, std error < 0.5 %
        assert weight[:, 0].mean() <= 1.0


def test_directional_albedo_from_sampling_matches_quadrature(mi):
    spec = make_bsdf("oren_nayar", sigma=0.8)
    bsdf = mi.load_dict(bsdf_dict(spec, 0.9))
    _, _, weight = _sample(mi, bsdf, 1.0, n=400_000, seed=7)
    # midpoint quadrature of the reference (as in test_reference)
    n = 256
    mu = (np.arange(n) + 0.5) / n
    ph = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    M, P = np.meshgrid(mu, ph, indexing="ij")
    s = np.sqrt(1 - M**2)
    wo = np.stack([s * np.cos(P), s * np.sin(P), M], -1)
    f = R.oren_nayar(np.broadcast_to(sph(1.0), wo.shape), wo, N_UP, 0.9, 0.8)
    quad = np.sum(f * M) / n * (np.pi / n)
    est = weight[:, 0].mean()
    sem = weight[:, 0].std() / np.sqrt(len(weight))
    assert abs(est - quad) < 4 * sem, (est, quad, sem)


@pytest.mark.parametrize(
    ("d", "theta_i"),
    [
        ({"type": "oren_nayar", "reflectance": 0.8, "sigma": 0.7}, 0.5),
        ({"type": "oren_nayar", "reflectance": 0.8, "sigma": 1.2, "model": "qualitative"}, 1.2),
        ({"type": "hapke", "reflectance": 0.2}, 0.8),
    ],
)
def test_chi2_sampling(mi, d, theta_i):
    chi2 = mi.chi2
    sample_func, pdf_func = chi2.BSDFAdapter(d["type"], d, wi=sph(theta_i).tolist())
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


def test_chi2_detects_a_wrong_pdf(mi):
    """The chi-square machinery must be able to fail: a pdf that disagrees with the sampler."""
    chi2 = mi.chi2
    d = {"type": "oren_nayar", "reflectance": 0.8, "sigma": 0.7}
    sample_func, pdf_func = chi2.BSDFAdapter("oren_nayar", d, wi=sph(0.5).tolist())

    def wrong_pdf(wo, *args):  # uniform hemisphere instead of cosine
        return pdf_func(wo, *args) * 0 + mi.Float(1 / (2 * np.pi)) * (wo.z > 0)

    test = chi2.ChiSquareTest(
        domain=chi2.SphericalDomain(),
        sample_func=sample_func,
        pdf_func=wrong_pdf,
        sample_dim=3,
        sample_count=50_000,
        res=31,
        seed=3,
    )
    assert not test.run(0.01, quiet=True)


# --- Hapke specifics ------------------------------------------------------------------------


@pytest.mark.parametrize("albedo", [0.03, 0.12, 0.3, 0.7])
def test_hapke_normal_albedo_matches_grid_value(mi, albedo):
    bsdf = mi.load_dict(bsdf_dict(make_bsdf("hapke"), albedo))
    v = eval_plugin(mi, bsdf, sph(np.array([0.0])), sph(np.array([0.0])))
    # pi f(0, 0) is the normal albedo; f*cos_o with cos_o = 1; table interpolation error only
    assert np.pi * v[0, 0] == pytest.approx(albedo, rel=2e-3)
    assert HAPKE_TABLE_SIZE >= 256


def test_hapke_plugin_opposition_surge(mi):
    theta = np.pi / 6

    def pair(g_deg):
        cpsi = (np.cos(np.radians(g_deg)) - np.cos(theta) ** 2) / np.sin(theta) ** 2
        return sph(np.array([theta])), sph(np.array([theta]), np.arccos(cpsi))

    ratio = {}
    for B0 in (1.0, 0.0):
        bsdf = mi.load_dict(bsdf_dict(make_bsdf("hapke", B0=B0), 0.12))
        v0 = eval_plugin(mi, bsdf, *pair(0.0))[0, 0]
        v10 = eval_plugin(mi, bsdf, *pair(10.0))[0, 0]
        ratio[B0] = v0 / v10
        wi, wo = pair(0.0)
        w = R.hapke_w_from_normal_albedo(0.12, replace(R.LUNAR_HAPKE, B0=B0))
        assert v0 == pytest.approx(
            R.hapke(wi, wo, N_UP, replace(R.LUNAR_HAPKE, w=w, B0=B0))[0] * wo[0, 2], rel=2e-3
        )
    assert ratio[1.0] > 1.2  # the surge: brighter at zero phase
    assert ratio[0.0] < 1.05  # no peak without it


def test_hapke_plugin_opposition_surges_match_the_closed_form(mi):
    """Shadow hiding and coherent backscatter at zero and a few degrees of phase: the plugin
    (float32) against the closed form written out in tests/render/test_reference_hapke.py."""
    from tests.render.test_reference_hapke import (
        SURGE,
        SURGE_PHASES_DEG,
        _closed_form_surge,
        _phase_pair,
    )

    k = SURGE
    spec = make_bsdf("hapke", w=k["w"], b=k["b"], c=k["c"], B0=k["B_S0"], h=k["h_S"],
                     theta_bar=0.0, B_C0=k["B_C0"], h_C=k["h_C"])  # fmt: skip
    d = bsdf_dict(spec, 0.5)
    assert (d["albedo_mode"], d["B_C0"], d["h_C"]) == ("w", k["B_C0"], k["h_C"])
    bsdf = mi.load_dict(d)
    plain = mi.load_dict(bsdf_dict(replace(spec, B0=0.0, B_C0=0.0), 0.5))
    for g_deg in SURGE_PHASES_DEG:
        wi, wo = (v[None] for v in _phase_pair(g_deg, k["theta"]))
        got = eval_plugin(mi, bsdf, wi, wo)[0, 0] / wo[0, 2]
        g = 2 * np.arcsin(np.linalg.norm(wi - wo) / 2)
        assert got == pytest.approx(_closed_form_surge(g, **k), rel=2e-4), g_deg
    # at zero phase the whole surge: single scattering x (1 + B_S0), everything x (1 + B_C0)
    wi = wo = sph(np.array([k["theta"]]))
    ratio = eval_plugin(mi, bsdf, wi, wo)[0, 0] / eval_plugin(mi, plain, wi, wo)[0, 0]
    want = _closed_form_surge(0.0, **k) / _closed_form_surge(0.0, **{**k, "B_S0": 0, "B_C0": 0})
    assert ratio == pytest.approx(want, rel=2e-4)
    # the shadow-hiding gain acts on the single scattering only, the coherent one on all
    assert 1 + k["B_C0"] < want < (1 + k["B_C0"]) * (1 + k["B_S0"])


def test_hapke_coherent_backscatter_normal_albedo_matches_grid_value(mi):
    # the normal-albedo table includes (1 + B_C0): pi f(0, 0) is still the grid value
    bsdf = mi.load_dict(bsdf_dict(make_bsdf("hapke", B_C0=0.6, h_C=0.01), 0.12))
    v = eval_plugin(mi, bsdf, sph(np.array([0.0])), sph(np.array([0.0])))
    assert np.pi * v[0, 0] == pytest.approx(0.12, rel=2e-3)


def test_reflectance_texture_varies_per_point(mi):
    """An albedo grid as a bitmap texture drives each point (the terrain path)."""
    grid = np.array([[0.05], [0.4]], dtype=np.float32)  # 2 rows x 1 col
    tex = {
        "type": "bitmap",
        "bitmap": mi.Bitmap(grid[..., None]),
        "raw": True,
        "filter_type": "nearest",
    }
    wi = sph(np.array([0.4, 0.4]))
    wo = sph(np.array([0.7, 0.7]), 2.0)
    uv = np.array([[0.5, 0.25], [0.5, 0.75]])
    for spec in (make_bsdf("oren_nayar", sigma=0.5), make_bsdf("hapke"), make_bsdf("lambert")):
        d = bsdf_dict(spec, tex)
        got = eval_plugin(mi, mi.load_dict(d), wi, wo, uv=uv)[:, 0]
        want = [
            reference_for(d, wi[k : k + 1], wo[k : k + 1], float(grid[k, 0]))[0] for k in range(2)
        ]
        np.testing.assert_allclose(got, want, rtol=2e-3)


# --- parameters, kernels, errors ------------------------------------------------------------


def test_traverse_updates_without_recompiling(mi):
    import drjit as dr

    bsdf = mi.load_dict(bsdf_dict(make_bsdf("oren_nayar", sigma=0.2), 0.5))
    wi, wo = angle_grid()
    params = mi.traverse(bsdf)
    assert "sigma" in params and "reflectance.value" in params

    def jit_kernels(fn):
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        try:
            dr.kernel_history()  # clear
            out = fn()
            hist = [k for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT]
        finally:
            dr.set_flag(dr.JitFlag.KernelHistory, False)
        return out, {k["hash"] for k in hist}

    before, k_before = jit_kernels(lambda: eval_plugin(mi, bsdf, wi, wo))
    params["sigma"] = 0.9
    params.update()
    after, k_after = jit_kernels(lambda: eval_plugin(mi, bsdf, wi, wo))
    np.testing.assert_allclose(
        after[:, 0],
        reference_for({"type": "oren_nayar", "sigma": 0.9}, wi, wo, 0.5),
        rtol=2e-4,
        atol=1e-7,
    )
    assert not np.allclose(before, after)
    # sigma is opaque: the new value runs through the very same kernel (same hash)
    assert k_before and k_after == k_before


def test_hapke_traverse_rebuilds_albedo_table(mi):
    bsdf = mi.load_dict(bsdf_dict(make_bsdf("hapke"), 0.12))
    params = mi.traverse(bsdf)
    for key in ("b", "c", "B0", "h", "theta_bar", "B_C0", "h_C", "reflectance.value"):
        assert key in params
    params["B0"] = 0.0
    params.update()
    v = eval_plugin(mi, bsdf, sph(np.array([0.0])), sph(np.array([0.0])))
    assert np.pi * v[0, 0] == pytest.approx(0.12, rel=2e-3)  # still the grid's normal albedo
    params["B_C0"] = 0.8  # the coherent surge: the table follows it too
    params.update()
    v = eval_plugin(mi, bsdf, sph(np.array([0.0])), sph(np.array([0.0])))
    assert np.pi * v[0, 0] == pytest.approx(0.12, rel=2e-3)


@pytest.mark.parametrize(
    ("d", "msg"),
    [
        ({"type": "oren_nayar", "sigma": 2.0}, "sigma"),
        ({"type": "oren_nayar", "sigma": -0.5}, "sigma"),
        ({"type": "oren_nayar", "model": "nope"}, "model"),
        ({"type": "hapke", "h": 0.0}, "h must be"),
        ({"type": "hapke", "b": 1.2}, "b must be"),
        ({"type": "hapke", "albedo_mode": "x"}, "albedo_mode"),
        ({"type": "hapke", "h_C": 0.0}, "h_C must be"),
        ({"type": "hapke", "B_C0": -0.1}, "B_C0 must be"),
    ],
)
def test_plugin_errors_name_the_field(mi, d, msg):
    with pytest.raises(Exception, match=msg):  # Mitsuba may re-raise our ValueError
        mi.load_dict(d)


def test_bsdf_dict_shapes_and_errors():
    assert bsdf_dict(make_bsdf("lambert"), 0.3) == {"type": "diffuse", "reflectance": 0.3}
    on = bsdf_dict(make_bsdf("oren_nayar", sigma=0.25, model="qualitative"), {"type": "bitmap"})
    assert on == {
        "type": "oren_nayar",
        "reflectance": {"type": "bitmap"},
        "sigma": 0.25,
        "model": "qualitative",
    }
    h = bsdf_dict(make_bsdf("hapke"), 0.1)
    assert h["albedo_mode"] == "normal" and h["reflectance"] == 0.1
    hw = bsdf_dict(make_bsdf("hapke", w=0.4), 0.1)
    assert hw["albedo_mode"] == "w" and hw["reflectance"] == 0.4
    with pytest.raises(ValueError, match="reflectance"):
        bsdf_dict(make_bsdf("lambert"), 1.5)
    with pytest.raises(ValueError, match="LambertBSDF, OrenNayarBSDF, HapkeBSDF, LunarLambert"):
        bsdf_dict("diffuse", 0.5)  # type: ignore[arg-type]


@pytest.mark.render
def test_render_plane_matches_reference(mi):
    """End to end: a plane under a directional light seen by an orthographic camera.

    With a delta light and direct illumination the pixel radiance is exactly
    E * f(wi, wo) * cos(theta_i), with no sampling noise.
    """
    theta_i = np.radians(50.0)
    wi = sph(theta_i, 0.0)
    for spec in (make_bsdf("oren_nayar", sigma=0.6), make_bsdf("hapke"), make_bsdf("lambert")):
        scene = mi.load_dict(
            {
                "type": "scene",
                "integrator": {"type": "direct"},
                "plane": {
                    "type": "rectangle",
                    "bsdf": bsdf_dict(spec, 0.3),
                    "to_world": mi.ScalarTransform4f().scale([10, 10, 1]),
                },
                "sun": {"type": "directional", "direction": (-wi).tolist(), "irradiance": 2.0},
                "cam": {
                    "type": "orthographic",
                    "to_world": mi.ScalarTransform4f().look_at(
                        origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]
                    ),
                    "film": {
                        "type": "hdrfilm",
                        "width": 4,
                        "height": 4,
                        "rfilter": {"type": "box"},
                    },
                    "sampler": {"type": "independent", "sample_count": 4},
                },
            }
        )
        img = np.array(mi.render(scene, spp=4))
        d = bsdf_dict(spec, 0.3)
        want = 2.0 * reference_for(d, wi[None], N_UP[None], 0.3)[0] * np.cos(theta_i)
        np.testing.assert_allclose(img[..., 0], want, rtol=2e-3)


# --- spatially varying sigma (paper Fig. 4: roughness from wavelet energy) -----------------


def _sigma_bitmap(mi, grid):
    return {
        "type": "bitmap",
        "data": mi.TensorXf(np.asarray(grid, np.float32)[..., None]),
        "raw": True,
        "filter_type": "nearest",
    }


@pytest.mark.parametrize("model", ["full", "qualitative"])
def test_constant_sigma_texture_is_bit_identical_to_scalar(mi, model):
    wi, wo = angle_grid()

    def scalar(sigma):
        spec = make_bsdf("oren_nayar", sigma=sigma, model=model)
        return eval_plugin(mi, mi.load_dict(bsdf_dict(spec, 0.6)), wi, wo)

    want = scalar(0.7)
    # the tolerance below separates sigma 0.7 from a sigma 0.1% away by a factor > 50
    assert np.max(np.abs(scalar(0.7007) - want) / np.abs(want).max()) > 50 * 8 * F32_EPS
    for tex in (
        {"type": "uniform", "value": 0.7},
        _sigma_bitmap(mi, np.full((3, 2), 0.7)),
    ):
        d = {"type": "oren_nayar", "reflectance": 0.6, "sigma": tex, "model": model}
        uv = np.full((len(wi), 2), 0.4)
        got = eval_plugin(mi, mi.load_dict(d), wi, wo, uv=uv)
        # same float32 formulas per lane as the opaque constants: bit-identical on LLVM; a
        # CUDA kernel may contract or fold them differently. The sigma-only factors C1..C4
        # (<= 4 roundings each) then differ by a few ulp and f = rho / pi * (C1 + C2 ... )
        # is a sum of positive-coefficient terms, so its relative difference stays within
        # the factors' plus the final roundings: 8 ulp bounds it.
        assert_within_ulps(got, want, 8)


def test_bitmap_sigma_eval_equals_reference_at_the_texel_hit(mi):
    grid = np.array([[0.05], [1.2]])  # 2 rows x 1 col: v < 0.5 -> 0.05, v > 0.5 -> 1.2
    d = {"type": "oren_nayar", "reflectance": 0.8, "sigma": _sigma_bitmap(mi, grid)}
    bsdf = mi.load_dict(d)
    wi, wo = angle_grid()
    for row, v in ((0, 0.25), (1, 0.75)):
        uv = np.tile([0.5, v], (len(wi), 1))
        got = eval_plugin(mi, bsdf, wi, wo, uv=uv)[:, 0]
        want = R.oren_nayar(wi, wo, N_UP, 0.8, float(grid[row, 0])) * wo[:, 2]
        np.testing.assert_allclose(got, want, rtol=2e-4, atol=1e-7)
    # the two texels really differ (sigma 0.05 is nearly Lambert, 1.2 is very rough)
    a = eval_plugin(mi, bsdf, wi, wo, uv=np.tile([0.5, 0.25], (len(wi), 1)))[:, 0]
    b = eval_plugin(mi, bsdf, wi, wo, uv=np.tile([0.5, 0.75], (len(wi), 1)))[:, 0]
    assert np.abs(a - b).max() > 0.05


@pytest.mark.render
def test_two_roughness_regions_on_a_plane_render_as_the_reference_predicts(mi):
    """A flat terrain, left half sigma 0.1, right half sigma 1.2, sun at 35 deg elevation,
    nadir orthographic view: each pixel is exactly E f(wi, n) cos(theta_i) with its cell's
    sigma (delta light, direct illumination, flat: no noise, no interreflection)."""
    from simlunar.geometry import OrthoCamera
    from simlunar.render.lights import SunLight
    from simlunar.render.materials import OrenNayarBSDF
    from simlunar.render.scene import TerrainScene
    from simlunar.terrain.types import Terrain

    shape = (6, 8)
    t = Terrain(np.zeros(shape), np.full(shape, 0.4, np.float32), 0.5, origin=(-2.0, 1.5))
    sigma = np.where(np.arange(shape[1]) < 4, 0.1, 1.2)[None].repeat(shape[0], 0)
    cam = OrthoCamera.nadir_for_grid(shape, t.spacing, t.origin, altitude=5.0)
    elev = np.radians(35.0)
    sun = [SunLight(elev, np.radians(90.0), irradiance=2.0)]
    img = TerrainScene(
        t, cam, lights=sun, bsdf=OrenNayarBSDF(0.3, sigma_map=sigma), max_depth=2, spp=4
    ).render()[..., 0]
    wi = sph(np.pi / 2 - elev)[None]
    ref = {
        s: 2.0 * R.oren_nayar(wi, N_UP[None], N_UP, 0.4, s)[0] * np.sin(elev) for s in (0.1, 1.2)
    }
    np.testing.assert_allclose(img[:, :4], ref[0.1], rtol=2e-3)
    np.testing.assert_allclose(img[:, 4:], ref[1.2], rtol=2e-3)
    # direction: for this geometry the reference makes the rough half darker, by > 10 %
    assert ref[1.2] < 0.9 * ref[0.1]
    assert img[:, 4:].mean() < 0.9 * img[:, :4].mean()


@pytest.mark.render
def test_scalar_and_constant_map_give_identical_images(mi):
    from simlunar.geometry import OrthoCamera
    from simlunar.render.lights import SunLight
    from simlunar.render.materials import OrenNayarBSDF
    from simlunar.render.scene import TerrainScene
    from simlunar.terrain.types import Terrain

    rng = np.random.default_rng(3)
    shape = (12, 10)
    t = Terrain(rng.normal(0, 0.2, shape), np.full(shape, 0.3, np.float32), 0.25, (0.0, 0.0))
    cam = OrthoCamera.nadir_for_grid(shape, t.spacing, t.origin, altitude=5.0)
    sun = [SunLight(np.radians(30.0), np.radians(60.0))]
    kw = {"lights": sun, "max_depth": 3, "spp": 8, "seed": 5}
    a = TerrainScene(t, cam, bsdf=OrenNayarBSDF(0.4), **kw).render()
    b = TerrainScene(t, cam, bsdf=OrenNayarBSDF(0.1, sigma_map=np.full(shape, 0.4)), **kw).render()
    # bit-identical on LLVM; on CUDA the two paths round the sigma factors differently (1 ulp
    # measured on an H100). Same seed, and Oren-Nayar sampling does not depend on sigma, so
    # both renders trace the same paths and only the path weights differ: each is a product
    # of <= 2 BSDF values (max_depth 3) a few ulp apart (see the eval test above), and a
    # pixel sums 8 such positive terms (<= 8 more roundings on different operands), so 16 ulp
    # relative bound every pixel.
    assert_within_ulps(b, a, 16)
    # ... and the map is not ignored: the scalar sigma of b's spec alone (0.1) gives an image
    # far outside that tolerance
    c = TerrainScene(t, cam, bsdf=OrenNayarBSDF(0.1), **kw).render()
    assert np.max(np.abs(c - a) / np.abs(a).max()) > 1e-3


def test_sigma_texture_range_is_validated(mi):
    with pytest.raises(Exception, match=r"sigma texture values .* \[0, pi/2\).*range \[0.2, 1.7\]"):
        mi.load_dict({"type": "oren_nayar", "sigma": _sigma_bitmap(mi, [[0.2, 1.7]])})
    with pytest.raises(Exception, match="sigma texture values"):
        mi.load_dict({"type": "oren_nayar", "sigma": {"type": "uniform", "value": -0.1}})
    bsdf = mi.load_dict({"type": "oren_nayar", "sigma": _sigma_bitmap(mi, np.full((2, 2), 0.3))})
    params = mi.traverse(bsdf)
    params["sigma.data"] = mi.TensorXf(np.array([[[0.2], [2.0]], [[0.2], [0.2]]], np.float32))
    with pytest.raises(ValueError, match="sigma texture values"):
        params.update()


def test_sigma_texture_update_through_traverse(mi):
    bsdf = mi.load_dict(
        {"type": "oren_nayar", "reflectance": 0.5, "sigma": _sigma_bitmap(mi, np.full((2, 2), 0.2))}
    )
    params = mi.traverse(bsdf)
    params["sigma.data"] = mi.TensorXf(np.full((2, 2, 1), 0.9, np.float32))
    params.update()
    wi, wo = angle_grid()
    got = eval_plugin(mi, bsdf, wi, wo, uv=np.full((len(wi), 2), 0.5))[:, 0]
    want = reference_for({"type": "oren_nayar", "sigma": 0.9}, wi, wo, 0.5)
    np.testing.assert_allclose(got, want, rtol=2e-4, atol=1e-7)


def test_bsdf_dict_sigma_map_becomes_a_nearest_bitmap(mi):
    m = np.array([[0.1, 0.2], [0.3, 0.4]])
    d = bsdf_dict(make_bsdf("oren_nayar", sigma=0.3, sigma_map=m), 0.5)
    assert d["sigma"]["type"] == "bitmap" and d["sigma"]["filter_type"] == "nearest"
    assert d["sigma"]["raw"] is True
    np.testing.assert_array_equal(np.array(d["sigma"]["data"])[..., 0], m.astype(np.float32))


def test_scene_rejects_a_sigma_map_of_the_wrong_shape(mi):
    from simlunar.geometry import OrthoCamera
    from simlunar.render.lights import AmbientLight
    from simlunar.render.materials import OrenNayarBSDF
    from simlunar.render.scene import TerrainScene
    from simlunar.terrain.types import Terrain

    t = Terrain(np.zeros((4, 5)), np.full((4, 5), 0.3, np.float32), 1.0, (0.0, 0.0))
    cam = OrthoCamera.nadir_for_grid(t.shape, 1.0, (0.0, 0.0), altitude=3.0)
    with pytest.raises(ValueError, match=r"bsdf.sigma_map has shape \(5, 4\).*\(4, 5\)"):
        TerrainScene(
            t, cam, lights=[AmbientLight(1.0)], bsdf=OrenNayarBSDF(0.2, sigma_map=np.zeros((5, 4)))
        )
