"""The run command's conventions: --dry-run writes nothing, warnings go to stderr and do not
stop a run, `simlunar figures` says what it redrew."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FAKE_CLI = Path(__file__).resolve().parent / "fake_cli.py"

EXP = """name: conv
terrain: {preset: aerial_1, scale: 0.125}
render: {light: {kind: sun, elevation_deg: 0.5}}
study: {strategies: [random, grid], densities: [0.5, 0.25], trials: 2, metrics: [mse]}
figures: {sparse_mesh_density: null, formats: [png]}
"""


def _cli(*args, cwd):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    return subprocess.run(
        [sys.executable, str(FAKE_CLI), *args], cwd=cwd, env=env, capture_output=True, text=True
    )


def test_dry_run_writes_nothing_and_warns_of_a_low_sun(tmp_path):
    (tmp_path / "e.yaml").write_text(EXP)
    r = _cli("run", "e.yaml", "--dry-run", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "dry run: nothing written; results would go to results/conv" in r.stdout
    assert "work units: 1 (0 already in the folder, 1 to compute)" in r.stdout
    assert "estimated time:" in r.stdout and "estimated peak memory:" in r.stdout
    assert "warning: render.light.elevation_deg: the sun at 0.5 deg" in r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e.yaml"]
    # a mistake stops the dry run as it would stop the run
    r = _cli("run", "e.yaml", "--dry-run", "--set", "study.trials=0", cwd=tmp_path)
    assert r.returncode == 2 and "--set study.trials:" in r.stderr


def test_a_warned_run_goes_on_and_figures_says_what_it_redrew(tmp_path):
    (tmp_path / "e.yaml").write_text(EXP)
    r = _cli("run", "e.yaml", "--out", "o", "--no-progress", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "warning: render.light.elevation_deg" in r.stderr
    pngs = sorted(p.name for p in (tmp_path / "o" / "figures").glob("*.png"))
    # captions.md, and not_drawn.md (no wavelet planner: no panels_unit<i>)
    notes = sorted(p.name for p in (tmp_path / "o" / "figures").glob("*.md"))
    assert pngs and notes == ["captions.md", "not_drawn.md"]
    r = _cli("figures", "o", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert f"up to date, not redrawn: {len(pngs) + 2} file(s) (use --force" in r.stdout
    assert "redrew" not in r.stdout
    (tmp_path / "o" / "figures" / pngs[0]).unlink()
    r = _cli("figures", "o", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("redrew ") and f"  {pngs[0]}" in lines
    r = _cli("figures", "o", "--force", cwd=tmp_path)
    assert f"redrew {len(pngs) + 2} file(s)" in r.stdout
