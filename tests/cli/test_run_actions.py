"""The work of ``simlunar run`` and ``simlunar figures`` called directly (the commands' own
tests, tests/cli/test_run.py, go through Typer): how the flags become overrides before
validation, and the refusals."""

from __future__ import annotations

from pathlib import Path

import pytest

from simlunar.cli import run_actions
from simlunar.errors import SimlunarError

EXPERIMENTS = Path(__file__).resolve().parents[2] / "experiments"
NO_FLAGS = {"pdf": False, "save_scans": False, "save_arrays": False}


def test_pdf_and_export_flags_are_overrides_validated_with_the_experiment():
    plain = run_actions._load(str(EXPERIMENTS / "lidar_rover_mast.yaml"), [], **NO_FLAGS)
    flagged = run_actions._load(
        str(EXPERIMENTS / "lidar_rover_mast.yaml"),
        ["study.trials=2"],
        pdf=True,
        save_scans=True,
        save_arrays=True,
    )
    assert list(plain.figures.formats) == ["png"] and not plain.study.save_scans
    assert list(flagged.figures.formats) == ["png", "pdf"]
    assert flagged.study.save_scans and flagged.study.save_arrays and flagged.study.trials == 2


def test_save_scans_is_refused_for_a_study_without_a_scan():
    with pytest.raises(SimlunarError, match="--save-scans: experiment 'quickstart' has a sampling"):
        run_actions._load(
            str(EXPERIMENTS / "quickstart.yaml"), [], **{**NO_FLAGS, "save_scans": True}
        )


def test_figures_of_a_missing_folder_is_one_user_error(tmp_path):
    with pytest.raises(SimlunarError, match="no such folder"):
        run_actions.redraw_figures(str(tmp_path / "absent"), pdf=False, force=False)


def test_a_dry_run_writes_nothing_and_estimates(tmp_path, capsys):
    out = tmp_path / "out"
    run_actions.run_experiment_command(
        str(EXPERIMENTS / "quickstart.yaml"),
        out=str(out),
        workers=None,
        scheduler=None,
        set_=["terrain.scale=0.0625"],
        progress=False,
        figures=False,
        flags={**NO_FLAGS, "dry_run": True},
    )
    assert not out.exists()
    assert "units" in capsys.readouterr().out
