"""The paper's score (eq. 4.3) and samples-for-equal-error (simlunar.metrics.score)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics import samples_for_equal_error, score
from simlunar.metrics.score import check_densities


def test_score_random_against_itself_is_exactly_one(rng):
    dens = [2.0**-i for i in range(1, 12)]
    errs = {"random": rng.random((11, 20)) + 0.1, "other": rng.random(11)}
    assert score(errs, dens)["random"] == 1.0


def test_score_hand_computed():
    # densities 1/2, 1/4 -> weights 2, 4; ratios e_ref / e = 2, 1 -> (2*2 + 4*1) / 6 = 4/3
    s = score({"random": [1.0, 1.0], "wavelet": [0.5, 1.0]}, [0.5, 0.25])
    assert s["wavelet"] == pytest.approx(4 / 3)
    # trials are averaged before the ratio: mean([0.25, 0.75]) = 0.5
    s2 = score({"random": [1.0, 1.0], "wavelet": [[0.25, 0.75], [1.0, 1.0]]}, [0.5, 0.25])
    assert s2["wavelet"] == pytest.approx(4 / 3)
    # the sparse density dominates: better only at 1/4 scores higher than better only at 1/2
    a = score({"random": [1.0, 1.0], "s": [0.5, 1.0]}, [0.5, 0.25])["s"]
    b = score({"random": [1.0, 1.0], "s": [1.0, 0.5]}, [0.5, 0.25])["s"]
    assert b > a


def test_score_edge_cases():
    s = score({"random": [0.0, 1.0], "exact": [0.0, 0.0]}, [0.5, 0.25])
    assert s["random"] == 1.0 and s["exact"] == np.inf


@pytest.mark.parametrize(
    ("errs", "dens", "match"),
    [
        ({"random": [1.0, 1.0]}, [0.5, 0.0], r"densities must lie in \(0, 1\]"),
        ({"random": [1.0, 1.0]}, [1.5, 0.5], r"densities must lie in \(0, 1\]"),
        ({"random": [1.0, 1.0]}, [], "empty"),
        ({"grid": [1.0, 1.0]}, [0.5, 0.25], "reference 'random' missing"),
        ({"random": [1.0, 1.0, 1.0]}, [0.5, 0.25], "must have shape"),
        ({"random": [1.0, np.nan]}, [0.5, 0.25], "finite"),
    ],
)
def test_score_bad_input(errs, dens, match):
    with pytest.raises(ValueError, match=match):
        score(errs, dens)


def test_samples_for_equal_error_power_law():
    # e_random = k^-1, e_s = 0.5 k^-1: the strategy reaches e_random(k) with k / 2 samples.
    ks = np.array([100.0, 200.0, 400.0, 800.0, 1600.0])
    out = samples_for_equal_error({"random": 1 / ks, "s": 0.5 / ks}, ks)
    np.testing.assert_allclose(out["random"], 1.0)
    # e_random(100) = 0.01 is above the strategy's largest error 0.005: no extrapolation
    assert np.isnan(out["s"][0])
    np.testing.assert_allclose(out["s"][1:], 0.5, rtol=1e-12)


def test_samples_for_equal_error_bad_ks():
    with pytest.raises(ValueError, match="distinct positive"):
        samples_for_equal_error({"random": [1.0, 2.0]}, [100, 100])


def test_check_densities():
    np.testing.assert_array_equal(check_densities([0.5, "0.25"]), [0.5, 0.25])
    with pytest.raises(ValueError, match=r"^densities is empty$"):
        check_densities([])
    with pytest.raises(ValueError, match=r"^densities must lie in \(0, 1\], got \[0\.5, 0\.0\]$"):
        check_densities([0.5, 0.0])


def test_samples_for_equal_error_from_a_single_sample():
    """Sample counts start at 1 (one sample is a valid plan): e_random = 1 / k and e_s = 1 / (2 k)
    at k = 1, 2, 4; e_random(2) = 1/2 is e_s(1) and e_random(4) = 1/4 is e_s(2), so the strategy
    needs half the samples there; e_random(1) = 1 is above e_s's range (NaN)."""
    ks = [1, 2, 4]
    out = samples_for_equal_error({"random": [1.0, 0.5, 0.25], "s": [0.5, 0.25, 0.125]}, ks)
    assert np.isnan(out["s"][0])
    np.testing.assert_allclose(out["s"][1:], 0.5, rtol=1e-12)
    with pytest.raises(ValueError, match="distinct positive"):
        samples_for_equal_error({"random": [1.0, 2.0]}, [0, 2])
