"""Preset overrides through config (``preset_params(name, overrides=...)``) and their key paths."""

import numpy as np
import pytest

from simlunar.config.terrain import PresetError
from simlunar.config.translate import preset_params
from simlunar.terrain import generate


def test_only_the_overridden_fields_change():
    base = preset_params("aerial_1", scale=0.25)
    p = preset_params(
        "aerial_1",
        scale=0.25,
        overrides={"fractal": {"rms_m": 0.05}, "rocks": {"albedo_contrast": 0.2}},
    )
    assert p.fractal.rms == 0.05 and p.rocks.albedo_contrast == 0.2
    # the rest of each overridden section is the preset's (deep merge, not replacement)
    assert p.fractal.hurst == base.fractal.hurst == 0.8
    assert p.fractal.rolloff == base.fractal.rolloff == 80.0
    assert p.rocks.d_max == base.rocks.d_max
    assert (p.rows, p.cols, p.spacing) == (base.rows, base.cols, base.spacing) == (250, 400, 0.2)
    assert p.craters == base.craters and p.albedo == base.albedo


def test_heights_are_linear_in_the_fbm_rms():
    # craters, rocks and albedo draw from their own seed streams and are stamped the same way
    # whatever the fBm amplitude, and the fBm is scaled to exactly its rms, so
    # h(r) = h(0) + r / 0.25 * (h(0.25) - h(0)) and std(h(0.25) - h(0)) = 0.25 m (the preset).
    res = {
        r: generate(
            preset_params("aerial_1", scale=0.0625, overrides={"fractal": {"rms_m": r}}), rng=5
        )
        for r in (0.0, 0.1, 0.25)
    }
    h = {r: v.terrain.heights for r, v in res.items()}
    fbm_part = h[0.25] - h[0.0]
    np.testing.assert_allclose(h[0.1] - h[0.0], 0.4 * fbm_part, atol=1e-12)
    assert fbm_part.std() == pytest.approx(0.25, rel=1e-3)
    assert [k.x for k in res[0.0].craters] == [k.x for k in res[0.25].craters]
    np.testing.assert_array_equal(res[0.0].terrain.albedo, res[0.25].terrain.albedo)


@pytest.mark.parametrize(
    ("overrides", "key", "problem"),
    [
        ({"fractal": {"rms_mm": 2}}, "fractal.rms_mm", "unknown key (valid keys: hurst, rms_m,"),
        ({"fractl": {"rms_m": 1}}, "fractl", "unknown key (valid keys: grid, fractal,"),
        ({"name": "x"}, "name", "unknown key"),
        ({"fractal": {"rms_m": -0.1}}, "fractal.rms_m", "Input should be greater than or equal"),
        ({"fractal": {"hurst": 1.0}}, "fractal.hurst", "Input should be less than 1"),
        ({"rocks": {"albedo_contrast": "x"}}, "rocks.albedo_contrast", "Input should be a valid"),
        ({"grid": {"rows": 3}}, "grid.rows", "Input should be greater than or equal to 16"),
        ({"rocks": 0.2}, "rocks", "Input should be a valid dictionary"),
    ],
)
def test_bad_overrides_name_their_key(overrides, key, problem):
    with pytest.raises(PresetError) as info:
        preset_params("moonyard", overrides=overrides)
    assert info.value.key == key
    assert info.value.problem.startswith(problem), info.value.problem
    assert str(info.value) == f"{key}: {info.value.problem}"
