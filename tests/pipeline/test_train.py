"""``simlunar train``: a training YAML -> a learned model file and its record, usable by name
from an experiment's ``learned`` strategy."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.config.loading import ConfigError, validate_data
from simlunar.config.training import load_training
from simlunar.features.learned import LearnedMap
from simlunar.pipeline import train as train_mod
from simlunar.study.sampling import run_sampling_study

ROOT = Path(__file__).resolve().parents[2]


def _synthetic_view(cfg):
    """A planted relation: the terrain is rough where the image is bright (no render)."""
    rng = np.random.default_rng(cfg.terrain.seed_index + 10 * int(cfg.render.light.elevation_deg))
    rows, cols = 48, 64
    bright = np.zeros((rows, cols))
    r0, c0 = rng.integers(8, 40), rng.integers(8, 56)
    bright[max(r0 - 8, 0) : r0 + 8, max(c0 - 8, 0) : c0 + 8] = 1.0
    depth = 0.01 * np.arange(cols)[None, :] + bright * rng.normal(0, 0.5, (rows, cols))
    image = (0.2 + 0.6 * bright + 0.02 * rng.random((rows, cols))).astype(np.float32)
    return image, depth


def _yaml(tmp_path, **over) -> Path:
    d = {
        "name": "tiny",
        "seed": 100,
        "experiments": [str(ROOT / "experiments" / "table1_aerial.yaml")],
        "scale": 0.25,
        "held_out_presets": ["aerial_2"],
        "terrain_seeds": 2,
        "sun_elevations_deg": [30, 60],
        "densities": ["1/16"],
        "options": {"layouts": 1, "pixels_per_example": 500, "max_iter": 10},
        "model": str(tmp_path / "models" / "tiny.joblib"),
    }
    d.update(over)
    path = tmp_path / "train.yaml"
    path.write_text(yaml.safe_dump(d))
    return path


def test_train_writes_a_model_with_its_record_and_a_study_uses_it(tmp_path, monkeypatch):
    monkeypatch.setattr(train_mod, "guide_view", _synthetic_view)
    res = CliRunner().invoke(app, ["train", str(_yaml(tmp_path))])
    assert res.exit_code == 0, res.output
    model = tmp_path / "models" / "tiny.joblib"
    record = json.loads(model.with_suffix(".json").read_text())
    prov = record["provenance"]
    assert prov["command"].startswith("simlunar train ")
    # 2 presets (aerial_2 held out) x 2 terrain seeds x 2 suns
    assert len(prov["examples"]) == record["examples"] == 8
    assert {e["preset"] for e in prov["examples"]} == {"aerial_1", "aerial_3"}
    assert prov["held_out_presets"] == ["aerial_2"] and prov["experiments"][0]["seed"] == 1
    assert len(record["input_sha256"]) == 8 and record["model_sha256"]
    assert record["densities"] == [1 / 16]
    LearnedMap.load(model)
    # the learned strategy of an experiment loads it by path
    cfg = validate_data(
        {"name": "t", "seed": 1, "terrain": {"preset": "aerial_1", "scale": 0.125},
         "study": {"strategies": ["random", "lloyd_uniform", "learned_lloyd"],
                   "strategy_options": {"learned_lloyd": {
                       "strategy": "learned", "placement": "lloyd",
                       "feature_opts": {"model": str(model)}}},
                   "densities": ["1/16"], "trials": 1, "metrics": ["mse"]}}
    )  # fmt: skip
    from simlunar.config import translate

    image, depth = _synthetic_view(validate_data({**cfg.model_dump(mode="json", by_alias=True)}))
    out = run_sampling_study(depth, image, translate.sampling_options(cfg.study), rng=0)
    assert np.isfinite(out.errors("mse")["learned_lloyd"]).all()


def _recon_view(cfg):
    """A planted image-height relation (as tests/reconstruction/test_learned.py), no render."""
    from scipy import ndimage

    rng = np.random.default_rng(cfg.terrain.seed_index + 10 * int(cfg.render.light.elevation_deg))
    shape = (48, 64)
    d = ndimage.gaussian_filter(rng.standard_normal(shape), 1.5)
    d /= d.std()
    depth = 50 + ndimage.gaussian_filter(rng.standard_normal(shape), 12) * 30 + d
    image = (0.5 + 0.15 * d).astype(np.float32)
    return image, depth


def test_train_a_learned_reconstruction_and_run_it_by_name(tmp_path, monkeypatch):
    from simlunar.reconstruction import Guide, reconstruct, run_reconstruction
    from simlunar.reconstruction.learned import FORMAT, LearnedReconstruction, feature_names

    monkeypatch.setattr(train_mod, "guide_view", _recon_view)
    path = _yaml(tmp_path, target="reconstruction", densities=["1/16", "1/32"],
                 options={"layouts": 1, "pixels_per_example": 1000, "max_iter": 30})  # fmt: skip
    res = CliRunner().invoke(app, ["train", str(path)])
    assert res.exit_code == 0, res.output
    model = tmp_path / "models" / "tiny.joblib"
    record = json.loads(model.with_suffix(".json").read_text())
    assert record["format"] == FORMAT and record["feature_names"] == list(feature_names())
    assert record["densities"] == [1 / 32, 1 / 16] and record["examples"] == 8
    assert record["provenance"]["training_config"]["target"] == "reconstruction"
    assert record["training_pixels"] == 8 * 2 * 1000
    LearnedReconstruction.load(model)
    # a held-out view (another terrain seed): better than linear, by name
    from types import SimpleNamespace as NS

    image, depth = _recon_view(NS(terrain=NS(seed_index=7), render=NS(light=NS(elevation_deg=30))))
    r, c = np.divmod(np.random.default_rng(0).choice(depth.size, 120, replace=False), 64)
    pts, vals = np.column_stack((r, c)), depth[r, c]
    out = run_reconstruction("learned", pts, vals, depth.shape, guide=Guide(image),
                             options={"model": str(model)})  # fmt: skip
    lin = reconstruct(pts, vals, depth.shape)
    assert np.mean((out.heights - depth) ** 2) < 0.5 * np.mean((lin - depth) ** 2)


def test_reconstruction_training_yaml_errors(tmp_path, monkeypatch):
    from simlunar.reconstruction import RECONSTRUCTIONS

    with pytest.raises(ConfigError, match="reconstruction: only with target: reconstruction"):
        load_training(_yaml(tmp_path, reconstruction={"with_shading": False}))
    with pytest.raises(ConfigError, match="target"):
        load_training(_yaml(tmp_path, target="maps"))
    monkeypatch.delitem(RECONSTRUCTIONS._entries, "shading", raising=False)
    with pytest.raises(ConfigError, match="with_shading: needs the reconstruction 'shading'"):
        load_training(_yaml(tmp_path, target="reconstruction",
                            reconstruction={"with_shading": True}))  # fmt: skip
    with pytest.raises(ConfigError, match="shading_options: only with with_shading"):
        load_training(_yaml(tmp_path, target="reconstruction",
                            reconstruction={"shading_options": {"gain": 1}}))  # fmt: skip
    # the map stays the default target
    cfg, _ = load_training(_yaml(tmp_path))
    assert cfg.target == "map" and cfg.reconstruction is None


def test_shipped_reconstruction_training_yaml_loads():
    cfg, exps = load_training(ROOT / "experiments" / "training" / "learned_recon_quarter.yaml")
    assert cfg.target == "reconstruction" and cfg.model.endswith(".joblib")
    assert cfg.seed not in {e.seed for e in exps} and cfg.scale <= 0.25


def test_train_says_rendered_i_of_n_then_fits_with_its_stages(tmp_path, monkeypatch):
    monkeypatch.setattr(train_mod, "guide_view", _synthetic_view)
    res = CliRunner().invoke(app, ["train", str(_yaml(tmp_path, densities=["1/16", "1/64"]))])
    assert res.exit_code == 0, res.output
    lines = res.stdout.splitlines()
    rendered = [ln.split(":")[0] for ln in lines if ln.startswith("rendered")]
    # 2 presets x 2 terrain seeds x 2 suns, each with the total
    assert rendered == [f"rendered {i}/8" for i in range(1, 9)]
    fit = lines[len(rendered) :]
    assert fit[0] == "fitting the learned map on 8 examples (2 densities)"
    # the fitting stage reaches its total (the first density may be shown too, at most
    # every 10 s); then the time and the two files
    assert fit[-4] == "fitting 2/2 densities"
    assert fit[-3].startswith("fitted in ") and fit[-3].endswith(" s")
    assert fit[-2].startswith("model:") and fit[-1].startswith("record:")


def test_train_of_a_reconstruction_reports_its_training_set_and_fit(tmp_path, monkeypatch):
    monkeypatch.setattr(train_mod, "guide_view", _recon_view)
    cfg, experiments = load_training(_yaml(tmp_path, target="reconstruction"))
    lines: list[str] = []
    train_mod.train_from_config(cfg, experiments, log=lines.append)
    assert lines[8] == "fitting the learned reconstruction on 8 examples (1 densities)"
    assert "training set 8/8 examples" in lines
    assert lines[-2:-1] == ["fitting 1/1 models"] and lines[-1].startswith("fitted in ")


def test_train_a_map_on_the_fused_reconstructions_error(tmp_path, monkeypatch):
    from simlunar.reconstruction import Guide

    seen = []

    def view(cfg, *, with_guide=False):
        image, depth = _recon_view(cfg)
        seen.append(with_guide)
        # the experiment's guide: here a co-located frame too (as render.guide_frames: camera)
        flat = np.full(image.shape, 0.5, np.float32)
        guide = Guide(image, flat=flat, frames=("sun", "camera"))
        return (image, depth, guide) if with_guide else (image, depth)

    monkeypatch.setattr(train_mod, "guide_view", view)
    res = CliRunner().invoke(app, ["train", str(_yaml(tmp_path))])
    assert res.exit_code == 0, res.output
    plain = json.loads((tmp_path / "models" / "tiny.json").read_text())
    assert "error_reconstruction" not in plain  # linear: the record of before
    assert "error_reconstruction" not in plain["provenance"]["training_config"]
    assert seen == [False] * 8
    path = _yaml(tmp_path, error_reconstruction="shading", model=str(tmp_path / "f.joblib"))
    res = CliRunner().invoke(app, ["train", str(path)])
    assert res.exit_code == 0, res.output
    record = json.loads((tmp_path / "f.json").read_text())
    assert seen[8:] == [True] * 8
    assert record["error_reconstruction"] == "shading"
    assert record["error_guide_frames"] == ["camera", "sun"]
    assert record["provenance"]["training_config"]["error_reconstruction"] == "shading"
    LearnedMap.load(tmp_path / "f.joblib")
