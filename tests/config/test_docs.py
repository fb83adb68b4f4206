"""The generated YAML reference: one table per section with type, unit (from the key's suffix)
and default; the block between the markers rewritten only when it changed; the JSON Schemas."""

from __future__ import annotations

import pytest

from simlunar.config.docs import (
    BEGIN,
    END,
    SCHEMA_KINDS,
    docs_block,
    json_schema,
    reference_markdown,
    schema_model,
    update_docs,
)
from simlunar.config.render import RenderCfg, SunLightCfg
from simlunar.config.scene import SceneCfg
from simlunar.config.schema import ExperimentCfg
from simlunar.config.terrain import TerrainPresetCfg


@pytest.fixture(scope="module")
def reference() -> str:
    return reference_markdown()


def test_rows_carry_type_unit_default_and_description(reference):
    lines = reference.splitlines()
    assert "| `spp` | integer |  | `16` |  |" in lines
    assert "| `elevation_deg` | number | deg | `30.0` | above the horizon (0 < e <= 90) |" in lines
    # a LIDAR key derived from its library declaration: the unit the key is written in, the
    # default converted from SI (2e-9 s), the declared doc with the unit
    assert (
        "| `fwhm_ns` | number | ns | `2.0` | full width at half maximum of the emitted pulse (0: "
        "an impulse; at most 10 us) (ns) |" in lines
    )
    assert any(
        line.startswith("| `pulse_energy_uj` | number or null | uJ | `null` |") for line in lines
    )
    assert "| `densities` | [number] |  | required |  |" in lines
    assert any(
        line.startswith("| `strategy_options` | {name: section} |  | `{}` |") for line in lines
    )


def test_sections_of_each_document_kind_once_each(reference):
    heads = [line for line in reference.splitlines() if line.startswith("### ")]
    assert heads == [
        "### Experiment YAML (`experiments/*.yaml`)",
        "### Scene YAML (`simlunar render`)",
        "### Terrain preset (`scenes/<preset>.yaml`, `terrain.overrides`)",
    ]
    assert reference.count("#### `render.light` (kind: sun)") == 1
    assert reference.count("#### `render.camera` (kind: perspective)") == 1
    # the union's members each get a table, under the field's path
    for kind in ("orthographic_nadir", "perspective", "rover_mast"):
        assert f"#### `render.camera` (kind: {kind})" in reference
    # the sun's docstring heads its table
    first = (SunLightCfg.__doc__ or "").strip().split("\n")[0]
    assert first in reference
    assert reference.endswith("\n") and not reference.endswith("\n\n")


def test_docs_block_and_update_docs(tmp_path, reference):
    doc = tmp_path / "experiments.md"
    doc.write_text(f"# Head\n\n{BEGIN}\nold table\n{END}\n\nTail text.\n")
    assert docs_block(doc.read_text()) == "old table\n"
    assert update_docs(doc) is True
    text = doc.read_text()
    assert text.startswith("# Head\n\n" + BEGIN + "\n") and text.endswith(END + "\n\nTail text.\n")
    assert docs_block(text) == reference
    assert update_docs(doc) is False  # already current: not rewritten
    assert docs_block("no markers here") is None
    (tmp_path / "plain.md").write_text("nothing\n")
    with pytest.raises(ValueError, match=r"plain\.md: no <!-- schema-reference:begin"):
        update_docs(tmp_path / "plain.md")


def test_schema_models_and_json_schemas():
    assert SCHEMA_KINDS == ("experiment", "scene", "preset")
    assert [schema_model(k) for k in SCHEMA_KINDS] == [ExperimentCfg, SceneCfg, TerrainPresetCfg]
    with pytest.raises(
        ValueError, match=r"^unknown schema kind 'render' \(valid: experiment, scene, preset\)$"
    ):
        schema_model("render")
    s = json_schema("preset")
    assert s["title"] == "simlunar preset"
    assert s["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert s["additionalProperties"] is False  # unknown keys are refused in editors too
    assert "RenderCfg" in json_schema()["$defs"] and RenderCfg.__name__ == "RenderCfg"
