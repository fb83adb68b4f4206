"""LoG energy map: the closed-form response to a Gaussian blob, zero on planes, and the map as
a planner (``log_energy`` and ``log_lloyd``) from the registries."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.features import MAPS, feature_map
from simlunar.features.log_energy import LogEnergyOptions, log_energy
from simlunar.planner import plan, planner_label


def _blob(s0: float, n: int = 129, amplitude: float = 100.0) -> np.ndarray:
    """amplitude * the normalised 2-D Gaussian of sigma s0 centred on pixel (n // 2, n // 2)."""
    r, c = np.mgrid[:n, :n] - n // 2
    return amplitude * np.exp(-(r * r + c * c) / (2 * s0 * s0)) / (2 * np.pi * s0 * s0)


@pytest.mark.parametrize("sigma", [2.0, 4.0, 8.0])
def test_centre_of_a_gaussian_blob_matches_the_closed_form(sigma):
    # G_s0 * G_sigma = G_t, t = s0^2 + sigma^2, and nabla^2 G_t(0) = -1 / (pi t^2), so the
    # scale-normalised response at the centre is -A sigma^2 / (pi t^2), squared here
    s0, a = 4.0, 100.0
    m = log_energy(_blob(s0, amplitude=a), sigma_px=sigma, scales=1)
    expect = (a * sigma**2 / (np.pi * (s0**2 + sigma**2) ** 2)) ** 2
    # within 3 %: the 5-point Laplacian on the pixel grid (measured 2.5 % low at sigma 2)
    assert m[64, 64] == pytest.approx(expect, rel=0.03)


def test_the_response_peaks_at_the_blobs_own_scale():
    # sigma^2 / (s0^2 + sigma^2)^2 is largest at sigma = s0 (Lindeberg's scale selection)
    img = _blob(4.0)
    centre = [log_energy(img, sigma_px=s, scales=1)[64, 64] for s in (1.0, 2.0, 4.0, 8.0, 16.0)]
    assert int(np.argmax(centre)) == 2


def test_planes_and_constants_give_zero_and_scales_add():
    assert np.all(log_energy(np.full((30, 40), 7.0)) == 0.0)
    # a plane: zero away from the borders (reflected there, so a ramp folds into a ridge)
    r, c = np.mgrid[:100, :120].astype(float)
    plane = 0.3 * r - 0.2 * c + 5.0
    m = log_energy(plane)  # scales 1, 2, 4 px: kernels reach 16 px
    assert np.max(m[20:-20, 20:-20]) < 1e-20
    img = np.random.default_rng(0).random((40, 50))
    total = log_energy(img, sigma_px=1.0, scales=3)
    parts = sum(log_energy(img, sigma_px=s, scales=1) for s in (1.0, 2.0, 4.0))
    np.testing.assert_allclose(total, parts)
    assert total.dtype == np.float64 and np.all(total >= 0)


@pytest.mark.parametrize(
    ("opts", "match"),
    [({"sigma_px": 0.0}, "sigma_px must be > 0"), ({"scales": 0}, "scales must be >= 1"),
     ({"scales": 1.5}, "scales must be an integer")],
)  # fmt: skip
def test_bad_options_are_refused(opts, match):
    with pytest.raises(ValueError, match=match):
        LogEnergyOptions(**opts)
    with pytest.raises(ValueError, match=match):
        feature_map("log_energy", np.zeros((8, 8)), **opts)


def test_registered_as_a_map_and_as_a_lloyd_planner():
    assert MAPS["log_energy"].options is LogEnergyOptions
    img = _blob(3.0, n=64)
    np.testing.assert_array_equal(feature_map("log_energy", img), log_energy(img))
    assert planner_label("log_lloyd") == "LoG energy, Lloyd"
    p = plan("log_lloyd", 60, image=img, rng=0, lloyd_iterations=5)
    assert np.unique(p.flat).size == 60
    # the layout follows the blob: more samples within 3 blob sigmas of its centre than the
    # uniform share of that disc (about 9 %)
    near = np.hypot(p.rows - 32, p.cols - 32) < 9
    assert near.sum() > 0.15 * 60
