"""``simlunar render`` end to end on a tiny scene: the default folder, the files it lists, the
ground truth of the scene's grid; a refusal before anything is written."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from simlunar.cli import app

SCENE = "name: tiny\nterrain: {preset: aerial_1, scale: 0.05}\nrender: {spp: 1}\n"


@pytest.mark.render
def test_render_writes_the_listed_files_into_the_default_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("scene.yaml").write_text(SCENE)
    r = CliRunner().invoke(app, ["render", "scene.yaml"])
    assert r.exit_code == 0, r.output
    out = Path("results") / "render" / "tiny"
    lines = r.stdout.splitlines()
    assert lines[-1] == f"rendered tiny into {out}"
    listed = dict(line.split() for line in lines[:-1])
    assert set(listed) >= {"radiance", "preview", "ground_truth", "scene"}
    for path in listed.values():
        assert Path(path).is_file() and Path(path).parent == out
    record = json.loads((out / "scene.json").read_text())
    assert record["config"]["name"] == "tiny" and list(record["shape"]) == [50, 80]
    with np.load(out / "ground_truth.npz") as gt:
        depth = gt["depth"]
    # aerial_1 is 1000 x 1600 cells; scale 0.05 keeps 50 x 80, one pixel per cell (nadir view)
    assert depth.shape == (50, 80)
    assert np.isfinite(depth).all()


def test_a_bad_variant_is_refused_before_anything_is_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("scene.yaml").write_text(SCENE)
    r = CliRunner().invoke(app, ["render", "scene.yaml"], env={"SIMLUNAR_VARIANT": "rgb_fast"})
    assert r.exit_code == 2
    assert r.stderr.startswith("error: SIMLUNAR_VARIANT=rgb_fast: unknown variant 'rgb_fast'")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.yaml"]
