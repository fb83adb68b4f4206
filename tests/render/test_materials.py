"""BSDF specs: registry, defaults and validation (NumPy only)."""

from __future__ import annotations

import math

import pytest

from simlunar.render import materials as M
from simlunar.render.reference import LUNAR_HAPKE


def test_registry_builds_each_spec():
    assert M.make_bsdf("lambert") == M.LambertBSDF()
    assert M.make_bsdf("oren_nayar", sigma=0.3) == M.OrenNayarBSDF(0.3, "full")
    on = M.make_bsdf("oren_nayar", sigma=0.3, model="qualitative")
    assert on.model == "qualitative" and on.name == "oren_nayar"
    h = M.make_bsdf("hapke")
    assert h.w is None and h.theta_bar == pytest.approx(LUNAR_HAPKE.theta_bar)
    assert (h.b, h.c, h.B0, h.h) == (LUNAR_HAPKE.b, LUNAR_HAPKE.c, LUNAR_HAPKE.B0, LUNAR_HAPKE.h)
    assert set(M.BSDFS) >= {"lambert", "oren_nayar", "hapke", "lunar_lambert"}


def test_specs_are_frozen_and_hold_no_albedo():
    on = M.OrenNayarBSDF(0.2)
    with pytest.raises(AttributeError):
        on.sigma = 0.5  # type: ignore[misc]
    for entry in M.BSDFS.values():
        cls = entry.target
        assert "albedo" not in {f for f in cls.__dataclass_fields__}


def test_unknown_name_lists_valid_names():
    with pytest.raises(
        ValueError, match="unknown BSDF 'phong'; valid: lambert, oren_nayar, hapke, lunar_lambert"
    ):
        M.make_bsdf("phong")


def test_unknown_parameter_names_it():
    with pytest.raises(ValueError, match=r"unknown parameter.*roughness.*valid: sigma, model"):
        M.make_bsdf("oren_nayar", roughness=0.2)


@pytest.mark.parametrize("sigma", [-0.01, math.pi / 2, 3.0, float("nan"), "abc"])
def test_sigma_out_of_range(sigma):
    with pytest.raises(ValueError, match="sigma"):
        M.make_bsdf("oren_nayar", sigma=sigma)


def test_sigma_edges_and_model():
    assert M.OrenNayarBSDF(0.0).sigma == 0.0
    assert M.OrenNayarBSDF(math.pi / 2 - 1e-9).sigma < math.pi / 2
    with pytest.raises(ValueError, match="model"):
        M.OrenNayarBSDF(0.1, model="fancy")


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("w", 1.5),
        ("w", -0.1),
        ("b", 1.0),
        ("b", -0.1),
        ("c", 1.5),
        ("B0", -1.0),
        ("h", 0.0),
        ("theta_bar", math.pi / 2),
        ("theta_bar", -0.1),
        ("h", float("inf")),
    ],
)
def test_hapke_validation_names_field(field, value):
    with pytest.raises(ValueError, match=f"^{field} must"):
        M.make_bsdf("hapke", **{field: value})


def test_hapke_accepts_explicit_w():
    assert M.HapkeBSDF(w=0.3, B0=0.0).w == 0.3


# --- per-cell roughness (paper Fig. 4) ----------------------------------------------------


def test_sigma_map_is_validated_copied_and_compared_by_value():
    import numpy as np

    m = np.array([[0.1, 0.2], [0.3, 0.4]])
    on = M.OrenNayarBSDF(0.3, sigma_map=m)
    m[0, 0] = 1.0  # the spec holds its own copy
    assert on.sigma_map[0, 0] == 0.1 and not on.sigma_map.flags.writeable
    assert on == M.OrenNayarBSDF(0.3, sigma_map=[[0.1, 0.2], [0.3, 0.4]])
    assert on != M.OrenNayarBSDF(0.3, sigma_map=[[0.1, 0.2], [0.3, 0.5]])
    assert on != M.OrenNayarBSDF(0.3)
    assert hash(on) == hash(M.OrenNayarBSDF(0.3))  # hashable; equal specs hash equal
    assert M.make_bsdf("oren_nayar", sigma=0.3, sigma_map=[[0.2]]).sigma_map.shape == (1, 1)


@pytest.mark.parametrize(
    ("value", "msg"),
    [
        ([[0.1, 1.6]], r"sigma_map values must be finite and in \[0, pi/2\).*\(0, 1\) = 1.6"),
        ([[-0.1, 0.2]], r"range \[-0.1, 0.2\]"),
        ([[0.1, float("nan")]], r"\(0, 1\) = nan"),
        ([0.1, 0.2], r"sigma_map must be a non-empty 2-D \(rows, cols\) array, got shape \(2,\)"),
        ([["a"]], "sigma_map must be a 2-D array of numbers"),
    ],
)
def test_sigma_map_errors_name_the_field(value, msg):
    with pytest.raises(ValueError, match=msg):
        M.OrenNayarBSDF(0.2, sigma_map=value)


def test_sigma_map_from_energy_hand_computed():
    import numpy as np

    # percentile 100 -> reference energy 4; normalised 0, .25, .5, 1
    e = np.array([[0.0, 1.0], [2.0, 4.0]])
    s = M.sigma_map_from_energy(e, sigma_min=0.2, sigma_max=0.6, percentile=100.0)
    np.testing.assert_allclose(s, [[0.2, 0.3], [0.4, 0.6]])
    # threshold 0.5: the cells at and above half the reference energy keep sigma_min
    s = M.sigma_map_from_energy(e, sigma_min=0.2, sigma_max=0.6, threshold=0.5, percentile=100.0)
    np.testing.assert_allclose(s, [[0.2, 0.3], [0.2, 0.2]])
    # the 50th percentile of (0, 1, 2, 4) is 1.5: 1/1.5 and clipping above it
    s = M.sigma_map_from_energy(e, sigma_min=0.0, sigma_max=0.3, percentile=50.0)
    np.testing.assert_allclose(s, [[0.0, 0.2], [0.3, 0.3]])
    # no energy at all: sigma_min everywhere
    z = M.sigma_map_from_energy(np.zeros((2, 3)), sigma_min=0.1, sigma_max=0.5)
    np.testing.assert_array_equal(z, np.full((2, 3), 0.1))


def test_sigma_map_from_energy_range_and_monotonicity(rng):
    import numpy as np

    e = rng.gamma(0.5, size=(40, 30))
    s = M.sigma_map_from_energy(e, sigma_min=0.1, sigma_max=0.7)
    assert s.min() >= 0.1 and s.max() <= 0.7 + 1e-12
    order = np.argsort(e, axis=None)
    assert np.all(np.diff(s.ravel()[order]) >= 0)  # monotone in the energy without threshold
    # 99th percentile normalisation: about 1 % of the cells saturate at sigma_max
    assert 0.005 < np.mean(s == 0.7) < 0.02
    M.OrenNayarBSDF(0.1, sigma_map=s)  # a valid map


@pytest.mark.parametrize(
    ("kw", "msg"),
    [
        ({"sigma_min": 0.5, "sigma_max": 0.2}, "sigma_min <= sigma_max"),
        ({"sigma_min": 0.1, "sigma_max": 1.6}, "< pi/2"),
        ({"sigma_min": 0.1, "sigma_max": 0.2, "threshold": 0.0}, "threshold must be in"),
        ({"sigma_min": 0.1, "sigma_max": 0.2, "percentile": 0.0}, "percentile must be in"),
    ],
)
def test_sigma_map_from_energy_errors(kw, msg):
    import numpy as np

    with pytest.raises(ValueError, match=msg):
        M.sigma_map_from_energy(np.ones((2, 2)), **kw)
    with pytest.raises(ValueError, match="energy must be finite and >= 0"):
        M.sigma_map_from_energy(-np.ones((2, 2)), sigma_min=0.1, sigma_max=0.2)
