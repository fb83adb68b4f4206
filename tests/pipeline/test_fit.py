"""The fitted-combination command on a result folder swept over terrain seeds."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.pipeline import fit as F
from simlunar.planner import NelderMeadOptions, ScoreProtocol

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    out = tmp_path_factory.mktemp("fit") / "fit_combination"
    r = CliRunner().invoke(
        app,
        [
            "run",
            str(ROOT / "experiments" / "fit_combination.yaml"),
            "--out",
            str(out),
            "--no-progress",
            "--set",
            "terrain.scale=0.0625",
            "--set",
            "render.spp=2",
            "--set",
            "study.trials=1",
            "--set",
            "sweep.seed=[1, 2, 3]",
        ],
    )
    assert r.exit_code == 0, r.output
    return out


def test_fit_reads_the_seeds_units_and_writes_a_report(results):
    report = F.run_fit(
        results,
        train_seeds=[1, 2],
        test_seeds=[3],
        protocol=ScoreProtocol(densities=(1 / 16, 1 / 64), trials=1),
        search=NelderMeadOptions(maxiter=4, restarts=0),
    )
    assert report["train_seeds"] == [1, 2] and report["test_seeds"] == [3]
    assert set(report["coefficients"]) == {"uniform", "gradient", "entropy", "wavelet", "saliency"}
    assert sum(report["coefficients"].values()) == pytest.approx(1.0)
    assert report["train_score"] >= report["train_score_start"]  # the start is a vertex
    assert set(report["test_scores"]) == {"fitted", "equal weights", *report["coefficients"]}
    assert json.loads((results / "fit.json").read_text()) == report
    md = (results / "fit.md").read_text()
    assert "| uniform | gradient | entropy | wavelet | saliency |" in md
    assert f"| fitted | {report['test_scores']['fitted']:.3f} |" in md


def test_fit_command_errors_name_the_problem(results, capsys):
    assert F.main([str(results), "--train-seeds", "1", "--test-seeds", "9"]) == 2
    assert "seeds [9] are not units" in capsys.readouterr().err
    assert F.main([str(results), "--train-seeds", "1", "--test-seeds", "1"]) == 2
    assert "must not overlap" in capsys.readouterr().err
    assert F.main([str(results / "nope"), "--train-seeds", "1", "--test-seeds", "2"]) == 2


def test_fit_with_lloyd_placement_writes_its_own_report(results, capsys):
    before = (results / "fit.json").read_bytes() if (results / "fit.json").exists() else None
    argv = [str(results), "--train-seeds", "1", "2", "--test-seeds", "3", "--maxiter", "2"]
    assert F.main([*argv, "--restarts", "0", "--trials", "1", "--placement", "lloyd"]) == 0
    report = json.loads((results / "fit_lloyd.json").read_text())
    assert report["placement"] == "lloyd" and report["trials"] == 1
    assert "placement halftone + Lloyd" in (results / "fit_lloyd.md").read_text()
    assert "placement halftone + Lloyd" in capsys.readouterr().out
    after = (results / "fit.json").read_bytes() if (results / "fit.json").exists() else None
    assert after == before  # the weighted draw's fit is not overwritten
    with pytest.raises(SystemExit) as exc:  # argparse's usage error: one line, exit 2
        F.main([*argv, "--placement", "halftone"])
    assert exc.value.code == 2
    assert "invalid choice: 'halftone'" in capsys.readouterr().err
