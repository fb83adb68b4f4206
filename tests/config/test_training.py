"""The training YAML of the learned map: the library's defaults, experiments read relative to the
file, held-out presets that exist and leave something to train on, one-line errors."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import pytest
import yaml
from pydantic import ValidationError
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.config.training import LearnedOptsCfg, TrainCfg, load_training
from simlunar.errors import ConfigError
from simlunar.features.learned import LearnedOptions

ROOT = Path(__file__).resolve().parents[2]


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


def test_training_options_are_the_library_defaults():
    assert LearnedOptsCfg().model_dump() == asdict(LearnedOptions())


def test_a_training_yaml_loads_with_its_experiments(tmp_path):
    cfg, experiments = load_training(_yaml(tmp_path, sun_elevations_deg=["0.5 rad"]))
    assert isinstance(cfg, TrainCfg) and cfg.densities == [1 / 16]
    assert cfg.sun_elevations_deg == [pytest.approx(28.64788975654116)]
    assert [e.name for e in experiments] == ["table1_aerial"]
    assert cfg.options.max_iter == 10 and cfg.options.max_leaf_nodes == 31


def test_experiment_paths_are_relative_to_the_training_file(tmp_path):
    (tmp_path / "exp").mkdir()
    (tmp_path / "exp" / "t1.yaml").write_text(
        (ROOT / "experiments" / "table1_aerial.yaml").read_text()
    )
    _, experiments = load_training(_yaml(tmp_path, experiments=["exp/t1.yaml"]))
    assert len(experiments) == 1
    path = _yaml(tmp_path, experiments=["exp/none.yaml"])
    with pytest.raises(ConfigError) as info:
        load_training(path)
    assert (
        str(info.value)
        == f"{path}: experiments[0]: file not found: {tmp_path / 'exp' / 'none.yaml'}"
    )


def test_training_yaml_errors_are_one_line(tmp_path):
    with pytest.raises(ConfigError, match=r"held_out_presets\[0\]: 'moonyard' is in none"):
        load_training(_yaml(tmp_path, held_out_presets=["moonyard"]))
    with pytest.raises(ConfigError, match="held_out_presets: leaves no preset"):
        load_training(_yaml(tmp_path, held_out_presets=["aerial_1", "aerial_2", "aerial_3"]))
    with pytest.raises(ConfigError, match=r"model: .*ends in \.joblib"):
        load_training(_yaml(tmp_path, model="m.pkl"))
    res = CliRunner().invoke(app, ["train", str(_yaml(tmp_path, densities=[]))])
    assert res.exit_code == 2 and "densities" in res.output


def test_more_refusals(tmp_path):
    lidar = str(ROOT / "experiments" / "lidar_descent_altimeter.yaml")
    path = _yaml(tmp_path, experiments=[lidar])
    with pytest.raises(ConfigError, match=r"experiments\[0\]: .* is not a sampling experiment$"):
        load_training(path)
    path = _yaml(tmp_path, densities=[0.25, "1/4"])
    with pytest.raises(ConfigError, match=r"densities: must be distinct, got \[0\.25, 0\.25\]$"):
        load_training(path)
    path.write_text("- a\n")
    with pytest.raises(ConfigError, match=r"train\.yaml: <root>: expected a mapping of keys$"):
        load_training(path)
    with pytest.raises(ValidationError, match="greater than or equal to 0"):
        TrainCfg(name="x", seed=-1, experiments=["e.yaml"], densities=[0.5], model="m.joblib")


def test_the_error_reconstruction_of_a_map_is_checked_and_recorded_only_when_not_linear():
    from simlunar.config.training import TrainCfg

    base = {"name": "t", "seed": 1, "experiments": ["x.yaml"], "densities": [0.1],
            "model": "m.joblib"}  # fmt: skip
    plain = TrainCfg(**base)
    assert plain.error_reconstruction == "linear" and "error_reconstruction" not in plain.recorded()
    fused = TrainCfg(**base, error_reconstruction={"shading": {"gain": 0.5}})
    assert fused.error_reconstruction_spec() == ("shading", {"gain": 0.5})
    assert fused.recorded()["error_reconstruction"] == {"shading": {"gain": 0.5}}
    assert TrainCfg(**base, error_reconstruction="shading").error_reconstruction_spec() == (
        "shading", {})  # fmt: skip
    for bad, match in (
        ({"error_reconstruction": "shadin"}, "unknown reconstruction 'shadin'"),
        ({"error_reconstruction": {"shading": {"gains": 1}}}, "gains"),
        ({"error_reconstruction": {"s2": {"reconstruction": "shading"}}}, "not a label"),
        ({"error_reconstruction": "shading", "target": "reconstruction"}, "only with target: map"),
    ):
        with pytest.raises(ValueError, match=match):
            TrainCfg(**base, **bad)
