"""`simlunar run ... | head -1`: a reader that closes stdout never kills a run; the run
finishes its work (every unit, the summary, the report) and stops printing."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TINY = ["--set", "study.strategies=[random]", "--set", "study.trials=1",
        "--set", "study.densities=[1/16]", "--set", "terrain.scale=0.05",
        "--set", "sweep={render.light.elevation_deg: [20, 40]}"]  # fmt: skip


def _run_with_stdout_closed(args, tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    with open(tmp_path / "stderr", "w") as err:
        proc = subprocess.Popen(
            [sys.executable, "-m", "simlunar.cli", *args],
            cwd=ROOT, stdout=subprocess.PIPE, stderr=err, env=env,
        )  # fmt: skip
        proc.stdout.close()  # the reader went away before the first line (head -0)
        rc = proc.wait(timeout=600)
    return rc, (tmp_path / "stderr").read_text()


def test_a_run_whose_reader_closed_stdout_finishes_its_work(tmp_path):
    out = tmp_path / "out"
    rc, err = _run_with_stdout_closed(
        ["run", "experiments/quickstart.yaml", "--out", str(out), "--no-progress",
         "--no-figures", *TINY], tmp_path)  # fmt: skip
    # before: exit 141 at the first line of the summary, report.html never written
    assert rc == 0, err
    assert "Traceback" not in err and "error" not in err
    assert (out / "report.html").is_file() and (out / "provenance.json").is_file()
    rows = list(csv.DictReader((out / "results.csv").read_text().splitlines()))
    assert {r["unit"] for r in rows} == {"0", "1"}


def test_a_dry_run_whose_reader_closed_stdout_exits_quietly(tmp_path):
    rc, err = _run_with_stdout_closed(
        ["run", "experiments/quickstart.yaml", "--out", str(tmp_path / "o"), "--dry-run", *TINY],
        tmp_path,
    )
    assert rc == 0, err
    assert "Traceback" not in err
    assert not (tmp_path / "o").exists()
