"""Inputs of a unit's figures (simlunar/pipeline/figure_inputs.py): the wavelet panels, the
sparse-mesh rebuild of Fig. 4 with a recording stand-in for the renderer (fast), the render lock,
and one tiny real render of the sparse mesh (marked ``render``)."""

from __future__ import annotations

import threading
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial import Delaunay

from simlunar.features import feature_map
from simlunar.pipeline import figure_inputs as fi
from simlunar.planner import DEFAULT_PLANNER, plan
from simlunar.render.materials import LambertBSDF, OrenNayarBSDF, sigma_map_from_energy
from simlunar.terrain.types import Terrain

SHAPE = (12, 16)


def _image(seed=0):
    rng = np.random.default_rng(seed)
    r, c = np.mgrid[0 : SHAPE[0], 0 : SHAPE[1]]
    return (np.sin(c / 2.0) * np.cos(r / 3.0) + 0.2 * rng.random(SHAPE)).astype(np.float32)


# --- panels -----------------------------------------------------------------------------------


def test_panel_energy_is_the_wavelet_feature_map():
    # the panels plan from the default planner's map; that planner is the wavelet one
    assert DEFAULT_PLANNER == "wavelet"
    img = _image()
    e = fi.panel_energy(img)
    assert e.shape == SHAPE and e.dtype == np.float64
    np.testing.assert_allclose(e, feature_map("wavelet", img), rtol=1e-12)


def test_panel_arrays_plan_size_dtypes_and_exact_plane_reconstruction():
    # depth is a plane: Delaunay-linear interpolation reproduces it exactly inside the hull of
    # the samples (nearest sample outside), and exactly at every sampled cell
    img = _image()
    r, c = np.mgrid[0 : SHAPE[0], 0 : SHAPE[1]]
    depth = 1.5 + 0.02 * r - 0.03 * c
    out = fi.panel_arrays(img, depth, fi.panel_energy(img), 0.1, rng=4)
    assert set(out) == {"wavelet_energy", "plan_rows", "plan_cols", "reconstruction"}
    assert out["wavelet_energy"].dtype == np.float32
    assert out["plan_rows"].dtype == out["plan_cols"].dtype == np.int32
    assert out["reconstruction"].dtype == np.float64 and out["reconstruction"].shape == SHAPE
    k = round(0.1 * img.size)  # 19 of 192 cells
    rows, cols = out["plan_rows"], out["plan_cols"]
    assert len(rows) == k and len({(a, b) for a, b in zip(rows, cols)}) == k
    rec = out["reconstruction"]
    np.testing.assert_allclose(rec[rows, cols], depth[rows, cols], rtol=1e-12)
    inside = Delaunay(np.c_[rows, cols]).find_simplex(np.c_[r.ravel(), c.ravel()]) >= 0
    inside = inside.reshape(SHAPE)
    assert inside.sum() > k
    np.testing.assert_allclose(rec[inside], depth[inside], rtol=1e-9)
    # the same rng gives the same plan
    again = fi.panel_arrays(img, depth, fi.panel_energy(img), 0.1, rng=4)
    np.testing.assert_array_equal(again["plan_rows"], rows)
    np.testing.assert_array_equal(again["plan_cols"], cols)


def test_panel_arrays_take_at_least_three_samples_and_fill_holes_with_the_mean():
    # density 0 still plans a triangle's worth (3); NaN depths (holes) read as the mean of the
    # rest, so a constant depth with holes reconstructs to that constant everywhere
    img = _image(1)
    depth = np.full(SHAPE, 2.5)
    depth[::2, ::3] = np.nan
    out = fi.panel_arrays(img, depth, fi.panel_energy(img), 0.0, rng=0)
    assert len(out["plan_rows"]) == 3
    np.testing.assert_allclose(out["reconstruction"], 2.5)


# --- RenderScene and the sparse mesh, with a stand-in renderer -----------------------------------


@pytest.fixture
def fake_render(monkeypatch):
    """Replace the renderer seen by :class:`RenderScene`: records each call's arguments and
    whether another thread could take the render lock meanwhile; returns pure red radiance."""
    calls = []

    def render(terrain, camera, **kw):
        other = []

        def try_lock():  # released by the thread that took it (an RLock has an owner)
            got = fi.RENDER_LOCK.acquire(blocking=False)
            if got:
                fi.RENDER_LOCK.release()
            other.append(got)

        t = threading.Thread(target=try_lock)
        t.start()
        t.join()
        calls.append(SimpleNamespace(terrain=terrain, camera=camera, lock_free=other[0], **kw))
        rgb = np.zeros((*terrain.heights.shape, 3), np.float32)
        rgb[..., 0] = 1.0
        return SimpleNamespace(image=rgb)

    monkeypatch.setattr(fi, "render", render)
    return calls


def _terrain():
    rng = np.random.default_rng(2)
    h = rng.normal(size=SHAPE)
    return Terrain(h, np.full(SHAPE, 0.3, np.float32), 0.1, (1.0, 2.0))


def test_render_scene_renders_its_settings_or_the_given_terrain_and_bsdf(fake_render):
    t, other = _terrain(), _terrain()
    scene = fi.RenderScene(t, "cam", ["sun"], LambertBSDF(), spp=3, seed=7, max_depth=2)
    scene.render()
    scene.render(other, bsdf="b2")
    a, b = fake_render
    assert (a.terrain, a.camera, a.lights, a.bsdf) == (t, "cam", ["sun"], scene.bsdf)
    assert (a.spp, a.seed, a.max_depth) == (3, 7, 2)
    assert (b.terrain, b.bsdf, b.spp) == (other, "b2", 3)


def test_sparse_mesh_render_rebuilds_from_the_planned_cells(fake_render, monkeypatch):
    t = _terrain()
    img = _image()
    energy = fi.panel_energy(img)
    on = OrenNayarBSDF(np.radians(20.0))
    scene = fi.RenderScene(t, "cam", [], on, spp=1, seed=0, max_depth=1)

    def no_energy(image):
        raise AssertionError("panel_energy recomputed although energy was given")

    monkeypatch.setattr(fi, "panel_energy", no_energy)
    lo, hi = np.radians(20.0), np.radians(45.0)
    out = fi.sparse_mesh_render(
        scene, img, density=0.2, rng=5, sigma_range=(lo, hi), threshold=0.8, energy=energy
    )
    assert set(out) == {"sparse_mesh_render", "sparse_mesh_render_rough", "sparse_mesh_sigma"}
    const, rough = fake_render
    # the rebuilt terrain keeps the heights of the planned cells (same plan for the same rng),
    # the albedo grid, spacing and origin; the other cells are interpolated, not copied
    p = plan(DEFAULT_PLANNER, round(0.2 * img.size), weights=energy, rng=5)
    sparse = const.terrain
    np.testing.assert_allclose(sparse.heights[p.rows, p.cols], t.heights[p.rows, p.cols])
    assert not np.allclose(sparse.heights, t.heights)
    np.testing.assert_array_equal(sparse.albedo, t.albedo)
    assert sparse.spacing == 0.1 and tuple(sparse.origin) == (1, 2)
    assert rough.terrain is sparse
    # constant roughness first, then the energy-modulated map with the scene's nominal sigma
    want = sigma_map_from_energy(energy, sigma_min=lo, sigma_max=hi, threshold=0.8)
    assert const.bsdf is on
    assert rough.bsdf == OrenNayarBSDF(on.sigma, on.model, sigma_map=want)
    np.testing.assert_allclose(out["sparse_mesh_sigma"], want, rtol=1e-6)
    assert out["sparse_mesh_sigma"].dtype == np.float32
    # the outputs are the Rec. 709 luminance of the radiance: pure red -> 0.2126
    np.testing.assert_allclose(out["sparse_mesh_render"], 0.2126, rtol=1e-6)
    # each render holds the lock: another thread could not take it meanwhile
    assert not const.lock_free and not rough.lock_free


def test_sparse_mesh_render_modulates_only_oren_nayar_with_a_range(fake_render):
    img = _image()
    lam = fi.RenderScene(_terrain(), "cam", [], LambertBSDF(), spp=1, seed=0, max_depth=1)
    assert set(fi.sparse_mesh_render(lam, img, density=0.1, rng=0, sigma_range=(0.1, 0.5))) == {
        "sparse_mesh_render"
    }
    on = fi.RenderScene(_terrain(), "cam", [], OrenNayarBSDF(0.3), spp=1, seed=0, max_depth=1)
    assert set(fi.sparse_mesh_render(on, img, density=0.1, rng=0)) == {"sparse_mesh_render"}
    assert len(fake_render) == 2


def test_render_lock_is_reentrant():
    # a unit that already holds the lock (e.g. around a panel) may render under it
    with fi.RENDER_LOCK, fi.RENDER_LOCK:
        pass


# --- one tiny real render (moved from test_unit.py) ---------------------------------------------


@pytest.mark.render
def test_sparse_mesh_render_constant_and_roughness_modulated():
    """Fig. 4: the sparse mesh rendered with constant and with energy-modulated roughness."""
    from scipy.ndimage import gaussian_filter

    from simlunar.features import feature_map
    from simlunar.geometry import OrthoCamera
    from simlunar.pipeline.figure_inputs import RenderScene, sparse_mesh_render
    from simlunar.render.lights import SunLight
    from simlunar.render.materials import LambertBSDF, OrenNayarBSDF, sigma_map_from_energy
    from simlunar.terrain.types import Terrain

    rng = np.random.default_rng(8)
    shape = (24, 32)
    h = gaussian_filter(rng.normal(size=shape), 1.5) * 2.0
    t = Terrain(h, np.full(shape, 0.3, np.float32), 0.1, (0.0, 0.0))
    cam = OrthoCamera.nadir_for_grid(shape, t.spacing, t.origin, altitude=10.0)
    sun = [SunLight(np.radians(30.0), np.radians(100.0))]
    image = rng.random(shape).astype(np.float32) * gaussian_filter(h, 1.0) ** 2
    on = OrenNayarBSDF(np.radians(20.0))
    kw = {"density": 1 / 8}

    def scene(bsdf):
        return RenderScene(t, cam, sun, bsdf, spp=2, seed=1, max_depth=2)

    lo, hi = np.radians(20.0), np.radians(45.0)
    out = sparse_mesh_render(scene(on), image, rng=3, sigma_range=(lo, hi), threshold=0.8, **kw)
    assert set(out) == {"sparse_mesh_render", "sparse_mesh_render_rough", "sparse_mesh_sigma"}
    want = sigma_map_from_energy(
        feature_map("wavelet", image), sigma_min=lo, sigma_max=hi, threshold=0.8
    )
    np.testing.assert_allclose(out["sparse_mesh_sigma"], want, rtol=1e-6)
    assert out["sparse_mesh_sigma"].min() >= lo - 1e-6 and out["sparse_mesh_sigma"].max() > lo
    rough, const = out["sparse_mesh_render_rough"], out["sparse_mesh_render"]
    assert rough.shape == const.shape == shape
    # only cells whose sigma differs from the scene's can change (same mesh, seed, samples)
    same = np.isclose(out["sparse_mesh_sigma"], on.sigma, rtol=0, atol=1e-7)
    assert same.any() and (~same).any()
    assert not np.allclose(rough[~same], const[~same], rtol=1e-3)
    # a degenerate range equal to the scene's sigma reproduces the constant render: exactly on
    # LLVM; a CUDA kernel rounds the texture path's sigma factors a few ulp differently from
    # the scalar path's (tests/render/test_bsdfs.py), and a pixel sums 2 spp of 1 BSDF value
    # each, so 16 float32 ulp relative bound it there (a 1e-5 relative change of sigma moves
    # BSDF values by 42-250 ulp on the eval grid of test_bsdfs.py; the check above covers the map)
    flat = sparse_mesh_render(scene(on), image, rng=3, sigma_range=(on.sigma, on.sigma), **kw)
    import mitsuba as mi  # the variant the renders above ran on

    if mi.variant().startswith("cuda"):
        diff = np.abs(flat["sparse_mesh_render_rough"].astype(np.float64) - const)
        assert np.all(diff <= 16 * np.finfo(np.float32).eps * np.abs(const))
    else:
        np.testing.assert_array_equal(flat["sparse_mesh_render_rough"], const)
    # the same plan (same rng) gives the same constant render; no modulation without a range
    # or for a BSDF without roughness
    plain = sparse_mesh_render(scene(on), image, rng=3, **kw)
    assert set(plain) == {"sparse_mesh_render"}
    np.testing.assert_array_equal(plain["sparse_mesh_render"], const)
    lam = sparse_mesh_render(scene(LambertBSDF()), image, rng=3, sigma_range=(lo, hi), **kw)
    assert set(lam) == {"sparse_mesh_render"}


# --- reconstruction panels ----------------------------------------------------------------------


def test_panel_planner_is_a_planner_the_study_ran():
    opts = {"wavelet_lloyd": {"strategy": "wavelet", "placement": "lloyd"},
            "seq": {"strategy": "sequential"}}  # fmt: skip
    assert fi.panel_planner(["random", "wavelet", "grid"], {}) == "wavelet"
    # no wavelet: the first label that plans without the truth and without measuring
    assert fi.panel_planner(["oracle_greedy", "seq", "wavelet_lloyd"], opts) == "wavelet_lloyd"
    assert fi.panel_planner(["lloyd_uniform"], {}) == "lloyd_uniform"
    assert fi.panel_planner(["oracle_greedy", "sequential"], {}) is None


def test_reconstruction_panels_reconstruct_one_plan_with_every_reconstruction():
    from simlunar.reconstruction import Guide, reconstruct
    from simlunar.study.sampling import SamplingStudyOptions

    img = _image()
    r, c = np.mgrid[0 : SHAPE[0], 0 : SHAPE[1]]
    depth = 50.0 - 0.1 * r - 0.05 * c + 0.02 * np.sin(c)  # a smooth, non-planar surface
    options = SamplingStudyOptions(
        strategies=("random", "wavelet_lloyd", "sequential_wavelet"),
        strategy_options={"wavelet_lloyd": {"strategy": "wavelet", "placement": "lloyd"},
                          "sequential_wavelet": {"strategy": "sequential"}},
        densities=(0.25,), trials=1, metrics=("mse",),
        reconstructions=("linear", "smoothed"),
    )  # fmt: skip
    arrays, meta = fi.reconstruction_panel_arrays(
        options, img, depth, 1 / 8, guide=Guide(img), rng=np.random.default_rng(3)
    )
    k = round(SHAPE[0] * SHAPE[1] / 8)
    # the study had no wavelet: the first planner that plans from the image alone drew it
    assert meta == {"recon_panels": {"planner": "random", "density": 0.125, "k": k,
                                     "reconstructions": ["linear", "smoothed"]}}  # fmt: skip
    rows, cols = arrays["recon_panel_rows"], arrays["recon_panel_cols"]
    assert len(rows) == k == len(set(zip(rows.tolist(), cols.tolist())))
    # linear is Delaunay-linear of the true depth at the planned pixels: exact there
    lin = arrays["recon_panel_0"]
    np.testing.assert_allclose(lin[rows, cols], depth[rows, cols], rtol=1e-6)
    expect = reconstruct(np.c_[rows, cols].astype(float), depth[rows, cols], SHAPE)
    np.testing.assert_allclose(lin, expect, rtol=1e-6)
    # the second reconstruction is another grid of the same samples, not a copy of linear
    assert arrays["recon_panel_1"].shape == SHAPE
    assert not np.allclose(arrays["recon_panel_1"], lin)
    # the same seed draws the same plan
    again, _ = fi.reconstruction_panel_arrays(
        options, img, depth, 1 / 8, guide=Guide(img), rng=np.random.default_rng(3)
    )
    np.testing.assert_array_equal(again["recon_panel_rows"], rows)


def test_reconstruction_panels_of_a_study_of_oracles_alone_are_empty():
    from simlunar.study.sampling import SamplingStudyOptions

    options = SamplingStudyOptions(strategies=("oracle_greedy",), densities=(0.25,), trials=1,
                                   metrics=("mse",))  # fmt: skip
    img = _image()
    assert fi.reconstruction_panel_arrays(options, img, img + 10.0, 1 / 8, guide=None,
                                          rng=0) == ({}, {})  # fmt: skip
