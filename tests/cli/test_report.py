"""``simlunar report`` as a command: its one-line refusals and the path it prints (the page
itself is tested in tests/results/test_report.py)."""

from __future__ import annotations

import os
from pathlib import Path

from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.results.store import FolderLock


def _invoke(*args):
    return CliRunner().invoke(app, ["report", *args])


def test_no_folder_is_one_line_exit_2(tmp_path):
    r = _invoke(str(tmp_path / "none"))
    assert r.exit_code == 2 and r.stderr == f"error: {tmp_path / 'none'}: no such folder\n"


def test_a_folder_that_is_no_result_is_refused_and_nothing_written(tmp_path):
    r = _invoke(str(tmp_path))
    assert r.exit_code == 2 and "provenance.json" in r.stderr
    assert r.stderr.count("\n") == 1 and list(tmp_path.iterdir()) == []


def test_prints_the_page_it_wrote(tmp_path, monkeypatch):
    written = []

    def fake(d):
        written.append(d)
        return Path(d) / "report.html"

    monkeypatch.setattr("simlunar.results.report.write_report", fake)
    r = _invoke(str(tmp_path))
    assert r.exit_code == 0 and r.stdout == f"{tmp_path / 'report.html'}\n"
    assert written == [str(tmp_path)]
    assert not (tmp_path / ".lock").exists()  # the lock is released


def test_waits_for_no_run(tmp_path):
    with FolderLock(tmp_path):
        r = _invoke(str(tmp_path))
    assert r.exit_code == 2 and f"pid {os.getpid()}" in r.stderr
