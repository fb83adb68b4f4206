"""The planner and placement registries: a planner is a map + a placement + options, named
apart from its map, and plan() reads everything from the entry."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.features import MAPS
from simlunar.planner import (
    PLACEMENTS,
    PLANNERS,
    LloydOptions,
    MapSource,
    map_of,
    plan,
    planner_label,
    planner_options,
)
from simlunar.planner.registry import combinable


def test_every_map_is_a_planner_and_variants_are_named_apart():
    for name in MAPS:
        assert PLANNERS[name].target == MapSource(name, "random")
    assert map_of("wavelet_lloyd") == "wavelet" and map_of("grid") is None
    assert PLANNERS["wavelet_lloyd"].options is LloydOptions is PLACEMENTS["lloyd"].options
    assert planner_label("wavelet_lloyd") == "Wavelet, Lloyd"
    assert combinable() == ("uniform", "gradient", "entropy", "wavelet", "saliency")


def test_a_named_variant_is_the_map_with_that_placement():
    img = np.random.default_rng(0).random((30, 40))
    a = plan("wavelet_lloyd", 50, image=img, rng=4)
    b = plan("wavelet", 50, image=img, rng=4, placement="lloyd")
    np.testing.assert_array_equal(a.flat, b.flat)
    c = plan("wavelet_lloyd", 50, image=img, rng=4, placement="random")
    d = plan("wavelet", 50, image=img, rng=4)
    np.testing.assert_array_equal(c.flat, d.flat)


def test_options_come_from_the_entries():
    assert planner_options("grid") == ()
    assert planner_options("wavelet", "lloyd") == (
        "placement", "density_power", "uniform_mix", "lloyd_iterations", "border_pitch",
        "feature_opts",
    )  # fmt: skip
    assert "coefficients" in planner_options("combination")
    with pytest.raises(ValueError, match=r"unknown option\(s\) \['border_pich'\] .*"
                       r"\(did you mean 'border_pitch'\?\)"):  # fmt: skip
        plan("lloyd_uniform", 10, shape=(10, 10), rng=0, border_pich=1.0)
    with pytest.raises(ValueError, match="measures while it plans"):
        plan("sequential", 10, shape=(10, 10), rng=0)
    with pytest.raises(ValueError, match=r"unknown strategy 'wavlet'.*did you mean 'wavelet'"):
        plan("wavlet", 10, shape=(10, 10), rng=0)
