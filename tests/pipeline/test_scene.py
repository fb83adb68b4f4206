"""``simlunar render``'s library side (simlunar/pipeline/scene.py): which folders it refuses,
and the files :func:`render_scene` writes, checked against a recording stand-in renderer (fast:
the real render of a tiny scene is covered by tests/cli/test_render.py and
tests/config/test_scene.py through the CLI)."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from simlunar.config.scene import SceneCfg
from simlunar.errors import ResultFolderError
from simlunar.imaging.exr import read_exr
from simlunar.pipeline import scene as sc
from simlunar.pipeline.unit import int_seed, stage_seeds

# --- check_render_folder -------------------------------------------------------------------------


def test_check_render_folder_accepts_new_empty_hidden_only_and_render_folders(tmp_path):
    sc.check_render_folder(tmp_path / "new")  # not there yet
    sc.check_render_folder(tmp_path)  # empty
    (tmp_path / ".DS_Store").write_text("")
    sc.check_render_folder(tmp_path)  # hidden files do not count
    render = tmp_path / "r"
    render.mkdir()
    (render / "scene.json").write_text("{}")
    (render / "radiance.exr").write_text("")
    sc.check_render_folder(render)  # a render folder of its own: rendered again
    f = tmp_path / "file"
    f.write_text("x")
    sc.check_render_folder(f)  # not a folder: left to mkdir to refuse


def test_check_render_folder_refuses_other_folders_in_one_line(tmp_path):
    exp = tmp_path / "exp"
    exp.mkdir()
    (exp / "config.yaml").write_text("name: x\n")
    with pytest.raises(
        ResultFolderError,
        match=rf"^--out {exp}: not empty and an experiment's result folder; choose an empty",
    ):
        sc.check_render_folder(exp)
    other = tmp_path / "other"
    other.mkdir()
    for name in ("b.txt", "a.txt"):
        (other / name).write_text("")
    # the first name in sorted order is the one named
    with pytest.raises(
        ResultFolderError, match=r"not a render folder \(no scene\.json, found a\.txt\)"
    ):
        sc.check_render_folder(other)


# --- render_scene with a stand-in renderer -----------------------------------------------------


@pytest.fixture
def fake_render(monkeypatch):
    """Record the renderer's arguments; return radiance and ground truth made from the grid."""
    calls = []

    def render(terrain, camera, **kw):
        rows, cols = terrain.heights.shape
        r, c = np.mgrid[0:rows, 0:cols]
        rgb = np.stack([r, c, r + c], -1).astype(np.float32) / (rows + cols) + 0.01
        depth = 10.0 - np.asarray(terrain.heights, np.float64)
        pos = np.stack([c * 1.0, -r * 1.0, np.asarray(terrain.heights, np.float64)], -1)
        nrm = np.broadcast_to([0.0, 0.0, 1.0], (rows, cols, 3)).copy()
        valid = np.ones((rows, cols), bool)
        valid[0, 0] = False
        gt = SimpleNamespace(depth=depth, position=pos, normal=nrm, valid=valid)
        calls.append(SimpleNamespace(terrain=terrain, camera=camera, gt=gt, image=rgb, **kw))
        return SimpleNamespace(image=rgb, gt=gt)

    monkeypatch.setattr(sc, "render", render)
    return calls


def _cfg(**render):
    return SceneCfg.model_validate(
        {
            "name": "tiny",
            "seed": 3,
            "terrain": {"preset": "aerial_1", "scale": 0.02},
            "render": {"spp": 2, "max_depth": 3, **render},
        }
    )


def test_render_scene_writes_every_file_from_the_render(tmp_path, fake_render):
    out = tmp_path / "o"
    paths = sc.render_scene(_cfg(sensor=None), out)
    (call,) = fake_render
    # the render's settings and its stage seed (the same stream as an experiment's unit)
    assert (call.spp, call.max_depth) == (2, 3)
    assert call.seed == int_seed(stage_seeds(3)["render"])
    assert set(paths) == {"radiance", "preview", "ground_truth", "ground_truth_npz", "scene"}
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in paths.values())
    # the ground truth round-trips: float64 / bool in the .npz, float32 channels in the .exr
    with np.load(paths["ground_truth_npz"]) as z:
        np.testing.assert_array_equal(z["depth"], call.gt.depth)
        np.testing.assert_array_equal(z["position"], call.gt.position)
        np.testing.assert_array_equal(z["normal"], call.gt.normal)
        assert z["valid"].dtype == bool and not z["valid"][0, 0] and z["valid"].sum() > 1
    exr = read_exr(paths["ground_truth"])
    assert set(exr) >= {"depth", "valid", "position.X", "position.Y", "position.Z", "normal.Z"}
    np.testing.assert_allclose(exr["position.Y"], call.gt.position[..., 1], rtol=1e-6)
    np.testing.assert_array_equal(exr["valid"], call.gt.valid.astype(np.float32))
    rad = read_exr(paths["radiance"])
    np.testing.assert_allclose(np.stack([rad["R"], rad["G"], rad["B"]], -1), call.image, rtol=1e-6)
    meta = json.loads(paths["scene"].read_text())
    assert meta["config"]["name"] == "tiny" and meta["config"]["seed"] == 3
    assert meta["shape"] == list(call.terrain.heights.shape)
    assert meta["terrain_s"] >= 0 and meta["render_s"] >= 0


def test_render_scene_adds_the_seeded_sensor_image(tmp_path, fake_render):
    a = sc.render_scene(_cfg(sensor={"bits": 8}), tmp_path / "a")
    b = sc.render_scene(_cfg(sensor={"bits": 8}), tmp_path / "b")
    assert a["sensor"].name == "sensor.png"
    # the sensor noise is drawn from the scene seed's sensor stream: the same file twice
    assert a["sensor"].read_bytes() == b["sensor"].read_bytes()
    # the default scene has a sensor; without one no sensor image is written
    assert _cfg().render.sensor is not None
    assert "sensor" not in sc.render_scene(_cfg(sensor=None), tmp_path / "c")


def test_render_scene_builds_the_units_terrain(tmp_path, fake_render):
    # the terrain is the one an experiment's unit builds from the same seed
    from simlunar.pipeline.unit import scene_inputs

    cfg = _cfg()
    sc.render_scene(cfg, tmp_path / "o")
    terrain, *_ = scene_inputs(cfg)
    np.testing.assert_array_equal(fake_render[0].terrain.heights, terrain.heights)
