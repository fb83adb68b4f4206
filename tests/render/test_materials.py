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
    assert set(M.BSDFS) == {"lambert", "oren_nayar", "hapke"}


def test_specs_are_frozen_and_hold_no_albedo():
    on = M.OrenNayarBSDF(0.2)
    with pytest.raises(AttributeError):
        on.sigma = 0.5  # type: ignore[misc]
    for cls in M.BSDFS.values():
        assert "albedo" not in {f for f in cls.__dataclass_fields__}


def test_unknown_name_lists_valid_names():
    with pytest.raises(ValueError, match="unknown BSDF 'phong'; valid: lambert, oren_nayar, hapke"):
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
