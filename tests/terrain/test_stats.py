"""Roughness statistics: hand-computed planes, random walks (H = 1/2 exactly), fBm, densities."""

import numpy as np
import pytest

from simlunar.terrain import Terrain
from simlunar.terrain.stats import feature_densities, roughness, terrain_report


def test_plane_has_its_gradient_as_slope_at_every_baseline_and_h_one():
    # z = 0.1 x + 0.05 y on a 0.5 m grid (rows run to -y)
    rows, cols, sp = 40, 50, 0.5
    x = (np.arange(cols) + 0.5) * sp
    y = -(np.arange(rows) + 0.5) * sp
    z = 0.1 * x[None, :] + 0.05 * y[:, None]
    r = roughness(z, sp, baselines_m=[0.5, 1.0, 2.0, 4.0])
    want = np.degrees(np.arctan(np.hypot(0.1, 0.05)))  # 6.379 deg
    np.testing.assert_allclose(r.median_slope_deg, want, rtol=1e-12)
    np.testing.assert_allclose(r.rms_slope_deg, want, rtol=1e-12)
    # nu(L) = L sqrt((0.1^2 + 0.05^2) / 2): linear in L, so H = 1
    np.testing.assert_allclose(r.nu_m, np.array([0.5, 1, 2, 4]) * np.sqrt(0.0125 / 2))
    assert r.hurst == pytest.approx(1.0, abs=1e-12)


def test_nodata_removes_only_the_pairs_touching_it():
    # a 45 deg plane rising to +y (north, row 0) with one spike cell made nodata
    z = np.tile(-np.arange(10.0)[:, None], (1, 10))
    z[4, 4] = 1e6
    assert roughness(z, 1.0, baselines_m=[1.0, 2.0]).rms_slope_deg[0] > 80
    z[4, 4] = np.nan
    r = roughness(z, 1.0, baselines_m=[1.0, 2.0])
    np.testing.assert_allclose(r.rms_slope_deg, 45.0)
    np.testing.assert_allclose(r.median_slope_deg, 45.0)


def test_random_walk_surface_has_hurst_one_half():
    # z = a(col) + b(row), a and b random walks with unit steps: nu(L)^2 = L exactly in
    # expectation along each axis, so nu ~ L^(1/2)
    rng = np.random.default_rng(7)
    n = 600
    a = np.cumsum(rng.normal(size=(1, n)), axis=1)
    b = np.cumsum(rng.normal(size=(n, 1)), axis=0)
    z = a + b
    r = roughness(z, 1.0, baselines_m=[1, 2, 4, 8, 16])
    assert r.hurst == pytest.approx(0.5, abs=0.06)
    assert r.nu_m[0] == pytest.approx(1.0, rel=0.1)  # one unit step: variance 1


def test_fbm_with_known_hurst_exponent_is_recovered():
    # spectral synthesis, independent of simlunar.terrain.fractal: P(k) ~ k^-(2H + 2)
    rng = np.random.default_rng(3)
    n = 512
    for H in (0.5, 0.8):
        kx = np.fft.fftfreq(n)[None, :]
        ky = np.fft.fftfreq(n)[:, None]
        k = np.hypot(kx, ky)
        k[0, 0] = np.inf
        amp = k ** (-(H + 1.0))
        phase = np.exp(2j * np.pi * rng.random((n, n)))
        z = np.real(np.fft.ifft2(amp * phase * rng.normal(size=(n, n))))
        r = roughness(z, 0.2, baselines_m=[0.2 * m for m in (1, 2, 4, 8, 16)])
        assert r.hurst == pytest.approx(H, abs=0.07), H


def test_bad_baselines_are_refused():
    z = np.zeros((10, 10))
    with pytest.raises(ValueError, match="whole number"):
        roughness(z, 1.0, baselines_m=[1.0, 1.5])
    with pytest.raises(ValueError, match="two baselines"):
        roughness(z, 1.0, baselines_m=[1.0])
    with pytest.raises(ValueError, match="does not fit"):
        roughness(z, 1.0, baselines_m=[1.0, 10.0])
    assert np.isnan(roughness(z, 1.0, baselines_m=[1.0, 2.0]).hurst)  # flat: no scaling


def test_feature_densities_count_cumulatively():
    d = feature_densities([0.1, 0.2, 0.6, 1.5], 50.0, thresholds_m=(0.1, 0.5, 2.0), per_m2=100)
    assert d == {0.1: 8.0, 0.5: 4.0, 2.0: 0.0}


def test_terrain_report_lines():
    from simlunar.config.translate import preset_params
    from simlunar.terrain import generate

    res = generate(preset_params("aerial_3"), rng=2, scale=0.05)
    lines = terrain_report(res.terrain, craters=res.craters, rocks=res.rocks)
    assert sum("°" in ln for ln in lines) >= 3
    assert any(ln.startswith("Hurst exponent H = ") for ln in lines)
    assert any(ln.startswith("craters per km^2") for ln in lines)
    t = Terrain(np.random.default_rng(0).normal(size=(32, 32)), np.ones((32, 32)), 1.0)
    assert "unknown" in terrain_report(t)[-1]
