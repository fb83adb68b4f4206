"""Terrain presets and an experiment's terrain section, built directly: preset lookup by name or
path, overrides deep-merged before validation with the override's key in the error, the cache
that follows the file, and the one-source rules of ``terrain``."""

from __future__ import annotations

import os

import pytest
import yaml
from pydantic import ValidationError

from simlunar.config.terrain import (
    PRESET_SECTIONS,
    SCENES,
    CratersCfg,
    PresetError,
    RocksCfg,
    TerrainCfg,
    TerrainOverridesCfg,
    TerrainPresetCfg,
    merged_preset,
    preset_data,
    preset_names,
    preset_path,
)


def test_the_shipped_presets():
    assert preset_names() == ["aerial_1", "aerial_2", "aerial_3", "moonyard"]
    assert "quickstart_scene" not in preset_names()  # a scene, not a preset
    assert preset_path("aerial_1") == SCENES / "aerial_1.yaml"
    p = merged_preset("aerial_1")
    assert isinstance(p, TerrainPresetCfg) and p.name == "aerial_1"
    assert (p.grid.rows, p.grid.cols, p.grid.spacing_m) == (1000, 1600, 0.2)
    assert set(PRESET_SECTIONS) == set(TerrainOverridesCfg.model_fields)


def test_unknown_presets_and_missing_files():
    with pytest.raises(PresetError) as info:
        preset_path("aerial_9")
    assert info.value.key is None
    assert str(info.value) == (
        "unknown terrain preset 'aerial_9' (valid: aerial_1, aerial_2, aerial_3, moonyard)"
        " (did you mean 'aerial_1', 'aerial_2' or 'aerial_3'?)"
    )
    with pytest.raises(PresetError, match=r"^terrain preset file not found: nowhere/x\.yaml$"):
        preset_path("nowhere/x.yaml")


def test_overrides_are_merged_into_their_section_only():
    ov = TerrainOverridesCfg.model_validate({"fractal": {"rms_m": "5 cm"}, "grid": {"rows": 64}})
    assert ov.as_mapping() == {"fractal": {"rms_m": 0.05}, "grid": {"rows": 64}}
    p = merged_preset("aerial_1", ov)
    base = merged_preset("aerial_1")
    assert p.fractal.rms_m == pytest.approx(0.05) and p.grid.rows == 64
    assert p.fractal.hurst == base.fractal.hurst and p.grid.cols == base.grid.cols
    assert merged_preset("aerial_1", TerrainOverridesCfg()) == base


def test_an_override_that_breaks_the_preset_names_its_key():
    ov = TerrainOverridesCfg.model_validate({"craters": {"d_min_m": 50}})
    with pytest.raises(PresetError) as info:
        merged_preset("aerial_1", ov)
    assert info.value.key == "craters.d_max_m"
    assert info.value.problem == "the diameter range is empty (40.0 <= d_min_m 50.0)"
    with pytest.raises(ValidationError, match="greater than or equal to 16"):
        TerrainOverridesCfg.model_validate({"grid": {"rows": 8}})  # the field's own bound


def test_a_preset_file_by_path_and_its_cache_follows_the_file(tmp_path):
    data = yaml.safe_load((SCENES / "aerial_1.yaml").read_text())
    f = tmp_path / "mine.yaml"
    f.write_text(yaml.safe_dump({**data, "name": "mine"}))
    assert merged_preset(str(f)).name == "mine"
    assert preset_data(str(f))["name"] == "mine"
    st = f.stat()
    f.write_text(yaml.safe_dump({**data, "name": "changed"}))
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    assert preset_data(str(f))["name"] == "changed"


def test_an_invalid_preset_file_is_named_in_the_error(tmp_path):
    data = yaml.safe_load((SCENES / "aerial_1.yaml").read_text())
    data["albedo"]["mean"] = 2
    f = tmp_path / "bad.yaml"
    f.write_text(yaml.safe_dump(data))
    with pytest.raises(PresetError) as info:
        merged_preset(str(f))
    assert info.value.key is None
    assert str(info.value) == f"{f}: albedo.mean: Input should be less than or equal to 1"
    g = tmp_path / "list.yaml"
    g.write_text("- 1\n- 2\n")
    with pytest.raises(PresetError, match=r"list\.yaml: <root>: expected a mapping of keys$"):
        preset_data(str(g))


def test_populations_check_their_range_and_law():
    assert CratersCfg(d_min_m="50 cm").d_min_m == 0.5
    with pytest.raises(ValidationError, match=r"d_max_m: the diameter range is empty \(3\.0"):
        RocksCfg(d_min_m=3.0, d_max_m=3.0)


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({}, "give exactly one of preset or file"),
        ({"preset": "aerial_1", "file": "x.npy"}, "give exactly one of preset or file"),
        ({"preset": "aerial_1", "albedo_file": "a.png"},
         "albedo_file goes with a DEM file (give terrain.file)"),
        ({"file": "x.npy", "overrides": {"grid": {"rows": 32}}},
         "overrides: overrides apply to a preset only (give terrain.preset)"),
        ({"preset": "aerial_1", "overrides": {"craters": {"d_min_m": 50}}},
         "overrides.craters.d_max_m: the diameter range is empty (40.0 <= d_min_m 50.0)"),
        ({"preset": "aerial_9"}, "preset: unknown terrain preset 'aerial_9'"),
        ({"file": "x.npy", "seed_index": 2},
         "seed_index applies to a preset, or to a DEM file with rocks (a DEM file alone has one "
         "terrain)"),
        ({"preset": "aerial_1", "spacing_m": 0.5},
         "spacing_m: the cell size of a DEM file (terrain.file) has no effect on a preset"),
        ({"file": "x.npy", "scale": 0.5},
         "scale: shrinks a preset's grid and has no effect on a DEM file (terrain.file)"),
    ],
)  # fmt: skip
def test_the_terrain_sections_rules(kw, message):
    with pytest.raises(ValidationError) as info:
        TerrainCfg.model_validate(kw)
    assert message in info.value.errors()[0]["msg"]


def test_terrain_sections_that_validate():
    t = TerrainCfg(preset="moonyard", seed_index=3, overrides={"fractal": {"rms_m": 0.1}})
    assert t.overrides.as_mapping() == {"fractal": {"rms_m": 0.1}}
    assert TerrainCfg(file="x.npy", spacing_m="20 cm").spacing_m == pytest.approx(0.2)
