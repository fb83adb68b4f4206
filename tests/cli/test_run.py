"""``simlunar run`` and ``simlunar figures`` as commands: what they hand the pipeline (options,
the result folder, --pdf as figures.formats), what they print, and their one-line refusals.
The pipeline itself is replaced by a recorder (it has its own tests)."""

from __future__ import annotations

import os
from pathlib import Path
from types import SimpleNamespace

import pytest
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.results.store import FolderLock

QUICKSTART = str(Path(__file__).resolve().parents[2] / "experiments" / "quickstart.yaml")


@pytest.fixture
def recorded(monkeypatch, tmp_path):
    """run_experiment replaced: the calls it got, and a summary of 3 units."""
    calls = []

    def fake_run(cfg, out_dir, *, executor, progress, figures):
        calls.append({"cfg": cfg, "out": out_dir, "progress": progress, "figures": figures,
                      "executor": executor})  # fmt: skip
        return SimpleNamespace(
            scores_markdown="| strategy | score |", notes=["note: one"], units_total=3,
            units_cached=1, units_computed=2, elapsed_s=1.25, figures=figures,
            figures_dir=Path(out_dir) / "figures",
        )  # fmt: skip

    monkeypatch.setattr("simlunar.pipeline.runner.run_experiment", fake_run)
    # the report of the (absent) folder: its own tests write real ones
    monkeypatch.setattr("simlunar.results.report.write_report", lambda d: Path(d) / "report.html")
    monkeypatch.chdir(tmp_path)
    return calls


def _invoke(*args):
    return CliRunner().invoke(app, list(args))


def test_run_hands_the_pipeline_the_experiment_and_prints_the_summary(recorded):
    r = _invoke("run", QUICKSTART, "--no-progress", "--set", "study.trials=2")
    assert r.exit_code == 0, r.output
    (call,) = recorded
    assert call["cfg"].name == "quickstart" and call["cfg"].study.trials == 2
    assert call["out"] == Path("results") / "quickstart"  # the default folder
    assert call["progress"] is False and call["figures"] is True
    assert r.stdout.splitlines() == [
        "| strategy | score |",
        "note: one",
        "work units: 3 (1 cached, 2 computed) in 1.2 s",
        "results: results/quickstart",
        "figures: results/quickstart/figures",
        "report: results/quickstart/report.html",
    ]


def test_pdf_adds_pdf_figures_and_no_figures_draws_none(recorded, tmp_path):
    r = _invoke("run", QUICKSTART, "--pdf", "--no-figures", "--out", str(tmp_path / "o"))
    assert r.exit_code == 0, r.output
    (call,) = recorded
    assert list(call["cfg"].figures.formats) == ["png", "pdf"]
    assert call["out"] == tmp_path / "o" and call["figures"] is False
    assert "figures:" not in r.stdout


@pytest.mark.parametrize(
    ("args", "line"),
    [
        (("--save-scans",), "error: --save-scans: experiment 'quickstart' has a sampling "
                            "study; scans are exported by scanner and lidar studies only"),
        (("--workers", "2", "--scheduler", "tcp://127.0.0.1:1"),
         "error: give either --workers or --scheduler, not both"),
        (("--set", "study.trials"), "error: --set study.trials: expected key.path=value"),
        (("--set", "study.trials=0"),
         "error: --set study.trials: Input should be greater than or equal to 1"),
    ],
)  # fmt: skip
def test_run_refusals_are_one_line_before_the_pipeline(args, line, recorded):
    r = _invoke("run", QUICKSTART, *args)
    assert r.exit_code == 2
    assert r.stderr == line + "\n"
    assert recorded == [] and not Path("results").exists()


@pytest.fixture
def drawn(monkeypatch):
    calls = []

    def fake_write(results_dir, *, formats, force):
        calls.append((results_dir, formats, force))
        out = Path(results_dir) / "figures" / "a.png"
        out.parent.mkdir(exist_ok=True)
        out.write_bytes(str(len(calls)).encode())  # drawn (written) on every call
        return [out]

    monkeypatch.setattr("simlunar.results.figures.write_figures_pruned", fake_write)
    return calls


def test_figures_redraws_with_the_folders_formats_or_pdf(tmp_path, drawn):
    r = _invoke("figures", str(tmp_path))
    assert r.exit_code == 0, r.output
    assert r.stdout == f"redrew 1 file(s) in {tmp_path / 'figures'}:\n  a.png\n"
    r = _invoke("figures", str(tmp_path), "--pdf", "--force")
    assert drawn == [(str(tmp_path), None, False), (str(tmp_path), ("png", "pdf"), True)]
    assert not (tmp_path / ".lock").exists()  # the lock is released


def test_figures_waits_for_no_run(tmp_path, drawn):
    with FolderLock(tmp_path):  # a run writing into the folder
        r = _invoke("figures", str(tmp_path))
    assert r.exit_code == 2 and drawn == []
    assert r.stderr == (
        f"error: {tmp_path}: another simlunar run (pid {os.getpid()}) is writing into this "
        f"folder (lock {tmp_path / '.lock'}); wait for it to finish or choose another --out\n"
    )


def test_figures_of_no_folder(tmp_path, drawn):
    r = _invoke("figures", str(tmp_path / "none"))
    assert r.exit_code == 2 and r.stderr == f"error: {tmp_path / 'none'}: no such folder\n"
