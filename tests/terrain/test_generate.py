"""generate(): seeds, finiteness, presets, scaling, albedo, parameter errors, feature counts."""

import numpy as np
import pytest
from pydantic import ValidationError

from simlunar.config.messages import format_validation_error
from simlunar.config.terrain import TerrainPresetCfg, preset_names
from simlunar.config.translate import preset_params
from simlunar.terrain import TerrainParams, generate
from simlunar.terrain.params import AlbedoParams, CraterParams, FractalParams, RockParams


def _small(**kw):
    base = dict(
        rows=120,
        cols=160,
        spacing=0.2,
        craters=CraterParams(law="trask", d_min=0.8, d_max=10.0),
        rocks=RockParams(law="high_blockiness", d_min=0.3, d_max=2.0),
    )
    return TerrainParams(**(base | kw))


def test_same_seed_identical_different_seed_differs():
    a = generate(_small(), rng=3)
    b = generate(_small(), rng=3)
    c = generate(_small(), rng=4)
    np.testing.assert_array_equal(a.terrain.heights, b.terrain.heights)
    np.testing.assert_array_equal(a.terrain.albedo, b.terrain.albedo)
    assert [k.x for k in a.craters] == [k.x for k in b.craters]
    assert not np.array_equal(a.terrain.heights, c.terrain.heights)
    assert not np.array_equal(a.terrain.albedo, c.terrain.albedo)


def test_finite_and_types():
    t = generate(_small(), rng=0).terrain
    assert t.heights.dtype == np.float64 and t.albedo.dtype == np.float32
    assert np.isfinite(t.heights).all() and np.isfinite(t.albedo).all()
    assert 0 < t.albedo.min() and t.albedo.max() <= 1
    assert not t.nodata.any()


def test_stages_use_independent_streams():
    # switching rocks off leaves the craters (and base) untouched
    with_rocks = generate(_small(), rng=9)
    without = generate(_small(rocks=RockParams(enabled=False)), rng=9)
    assert [k.x for k in with_rocks.craters] == [k.x for k in without.craters]
    assert without.rocks == []
    assert np.all(with_rocks.terrain.heights >= without.terrain.heights)


def test_crater_count_per_area_over_a_large_sample():
    # Trask: N(>D) = 10^-1.1 D^-2 per m^2. Grid 400 x 400 m at 1 m; D in [2, 20] m.
    p = TerrainParams(
        rows=400,
        cols=400,
        spacing=1.0,
        craters=CraterParams(law="trask", d_min=2.0, d_max=20.0),
        rocks=RockParams(enabled=False),
    )
    res = generate(p, rng=1)
    inside = [k for k in res.craters if 0 <= k.x <= 400 and -400 <= k.y <= 0]
    want = 400 * 400 * 10**-1.1 * (2.0**-2 - 20.0**-2)  # 3136
    assert abs(len(inside) - want) < 4 * np.sqrt(want)
    # craters centred outside the grid whose blanket reaches in are listed too
    assert any(not (0 <= k.x <= 400 and -400 <= k.y <= 0) for k in res.craters)
    d = np.array([k.diameter for k in inside])
    b = d.size / np.log(d / 2.0).sum()  # Pareto MLE, biased low by the truncation at 20 m
    assert 1.7 < b < 2.1


def test_uniform_albedo_switch_and_lunar_mean():
    u = generate(_small(albedo=AlbedoParams(uniform=True, mean=0.12)), rng=0).terrain
    assert np.all(u.albedo == np.float32(0.12))
    v = generate(_small(rocks=RockParams(enabled=False)), rng=0).terrain
    assert v.albedo.mean() == pytest.approx(0.12, rel=0.1)
    assert 0.01 < v.albedo.std() / v.albedo.mean() < 0.3  # mild variation


def test_fresh_ejecta_is_brighter():
    p = _small(
        rows=200,
        cols=200,
        craters=CraterParams(law="trask", d_min=4.0, d_max=8.0, max_age_myr=0.001),
        rocks=RockParams(enabled=False),
        albedo=AlbedoParams(variation=0.0, noise=0.0, ejecta_brightening=0.5),
    )
    res = generate(p, rng=2)
    a = res.terrain.albedo
    assert a.max() > 0.12 * 1.3 and a.min() == pytest.approx(0.12)


@pytest.mark.parametrize("name", ["aerial_1", "aerial_2", "aerial_3", "moonyard"])
def test_presets_load_and_generate_scaled(name):
    full = preset_params(name)
    assert full.name == name and full.description
    small = preset_params(name, scale=0.1)
    assert small.spacing == full.spacing
    assert small.rows == max(16, round(full.rows * 0.1))
    res = generate(preset_params(name), rng=0, scale=0.1)
    assert res.terrain.shape == (small.rows, small.cols)
    assert np.isfinite(res.terrain.heights).all()


def test_preset_sizes_match_the_paper():
    for n in ("aerial_1", "aerial_2", "aerial_3"):
        p = preset_params(n)
        assert (p.rows, p.cols, p.spacing) == (1000, 1600, 0.2)  # 5 voxels / m
    m = preset_params("moonyard")
    assert (m.rows, m.cols) == (971, 1674)
    assert m.cols * m.spacing == pytest.approx(2.0, abs=0.02)
    assert set(preset_names()) >= {"aerial_1", "aerial_2", "aerial_3", "moonyard"}


@pytest.mark.parametrize(
    ("patch", "field"),
    [
        ({"grid": {"spacing_m": -0.2}}, "grid.spacing_m"),
        ({"fractal": {"hurst": 1.2}}, "fractal.hurst"),
        ({"fractal": {"hurst": 0.0}}, "fractal.hurst"),
        ({"craters": {"d_min_m": 5.0, "d_max_m": 2.0}}, "craters.d_max_m"),
        ({"rocks": {"law": "boulders"}}, "unknown rocks law 'boulders'"),
        ({"craters": {"law": "nope"}}, "trask"),
        ({"craters": {"radius": 3}}, "craters.radius"),
        ({"albedo": {"mean": 1.5}}, "albedo.mean"),
        ({"extra": 1}, "extra"),
    ],
)
def test_bad_parameters_name_the_field(patch, field):
    # a preset file is read through the schema's models (config/), one line per error
    data = {"grid": {"rows": 32, "cols": 32, "spacing_m": 0.2}} | patch
    with pytest.raises(ValidationError) as info:
        TerrainPresetCfg.model_validate(data)
    assert field in format_validation_error(info.value, data, root=TerrainPresetCfg)


def test_bad_preset_names_and_files(tmp_path):
    with pytest.raises(ValueError, match="aerial_1"):
        preset_params("no_such_preset")
    with pytest.raises(ValueError, match=r"missing\.yaml"):
        preset_params(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("grid: {rows: 32, cols: 32, spacing_m: 0.2}\nfractal: {hurst: 2}\n")
    with pytest.raises(ValueError, match=r"bad\.yaml.*fractal\.hurst"):
        preset_params(bad)
    with pytest.raises(ValueError, match="scale"):
        preset_params("aerial_1", scale=0.0)
    with pytest.raises(TypeError, match="TerrainParams"):
        generate(42, rng=0)
    with pytest.raises(TypeError, match="preset_params"):
        generate("aerial_1", rng=0)  # presets are read in config/, not by the generator


def test_fractal_params_flow_through():
    p = _small(
        craters=CraterParams(enabled=False),
        rocks=RockParams(enabled=False),
        fractal=FractalParams(hurst=0.5, rms=0.7),
    )
    h = generate(p, rng=0).terrain.heights
    assert h.std() == pytest.approx(0.7)


def test_generator_rng_and_nodata_mask():
    a = generate(_small(), rng=np.random.default_rng(5)).terrain
    b = generate(_small(), rng=np.random.default_rng(5)).terrain
    np.testing.assert_array_equal(a.heights, b.heights)
    mask = np.zeros((120, 160), bool)
    mask[10:20, 30:40] = True
    t = generate(_small(), rng=5, nodata=mask).terrain
    np.testing.assert_array_equal(t.nodata, mask)
    assert np.isfinite(t.heights[~mask]).all() and np.isfinite(t.albedo).all()
    with pytest.raises(ValueError, match="nodata"):
        generate(_small(), rng=5, nodata=np.zeros((3, 3), bool))
