"""``simlunar train`` as a command: the training YAML checked first, the model path and the
command line handed to the pipeline, the two files it prints; refusals in one line. The
training itself is replaced by a recorder (tests/pipeline/test_train.py trains for real)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from simlunar.cli import app

ROOT = Path(__file__).resolve().parents[2]


def _yaml(tmp_path, **over) -> Path:
    d = {
        "name": "tiny", "seed": 100,
        "experiments": [str(ROOT / "experiments" / "table1_aerial.yaml")],
        "held_out_presets": ["aerial_2"], "densities": ["1/16"],
        "model": str(tmp_path / "models" / "tiny.joblib"),
    }  # fmt: skip
    d.update(over)
    path = tmp_path / "train.yaml"
    path.write_text(yaml.safe_dump(d))
    return path


@pytest.fixture
def recorded(monkeypatch):
    calls = []

    def fake_train(cfg, experiments, *, out, command, log):
        calls.append({"cfg": cfg, "experiments": experiments, "out": out, "command": command})
        log("training ...")
        model = Path(out or cfg.model)
        return model, model.with_suffix(".json")

    monkeypatch.setattr("simlunar.pipeline.train.train_from_config", fake_train)
    return calls


def test_train_hands_over_the_config_and_prints_the_files(tmp_path, recorded):
    path = _yaml(tmp_path)
    r = CliRunner().invoke(app, ["train", str(path), "--out", str(tmp_path / "m x.joblib")])
    assert r.exit_code == 0, r.output
    (call,) = recorded
    assert call["cfg"].name == "tiny" and [e.name for e in call["experiments"]] == ["table1_aerial"]
    assert call["out"] == str(tmp_path / "m x.joblib")
    # the command as a shell would take it back (quoted where needed), for the model's record
    assert call["command"] == f"simlunar train {path} --out '{tmp_path / 'm x.joblib'}'"
    assert r.stdout.splitlines() == [
        "training ...",
        f"model:  {tmp_path / 'm x.joblib'}",
        f"record: {tmp_path / 'm x.json'}",
    ]


def test_refusals_before_training(tmp_path, recorded):
    r = CliRunner().invoke(app, ["train", str(_yaml(tmp_path)), "--out", "m.pkl"])
    assert (
        r.exit_code == 2
        and r.stderr == "error: --out m.pkl: a learned model file ends in .joblib\n"
    )
    r = CliRunner().invoke(app, ["train", str(tmp_path / "none.yaml")])
    assert r.exit_code == 2
    assert r.stderr.startswith(f"error: experiment file not found: {tmp_path / 'none.yaml'}")
    assert r.stderr.count("\n") == 1  # one line (with a did-you-mean for train.yaml)
    assert recorded == []
