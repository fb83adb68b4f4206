"""Real work units end to end: terrain, Mitsuba render, sensor, sampling study, figures.

A shrunken quickstart (1/16-scale aerial scene 1: 62 x 100 cells, 4 spp, 3 strategies,
3 densities, 2 trials) keeps each unit to a few seconds on 2 cores.
"""

from __future__ import annotations

import csv
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from simlunar.cli import app

pytestmark = pytest.mark.render

ROOT = Path(__file__).resolve().parents[2]
QUICKSTART = str(ROOT / "experiments" / "quickstart.yaml")
SMALL = [
    "--set",
    "terrain.scale=0.0625",
    "--set",
    "render.spp=4",
    "--set",
    "study.strategies=[random, grid, wavelet]",
    "--set",
    "study.densities=[1/4, 1/16, 1/64]",
    "--set",
    "study.trials=2",
    "--set",
    "study.metrics=[mse, grad]",
]


def run_cli(*args):
    r = CliRunner().invoke(app, ["run", *args, "--no-progress"])
    assert r.exit_code == 0, r.output
    return r


@pytest.mark.slow
def test_quickstart_variant_end_to_end(tmp_path):
    out = tmp_path / "qs"
    r = run_cli(QUICKSTART, "--out", str(out), *SMALL)
    # the quickstart reconstructs every plan twice: one score block per reconstruction
    assert "| reconstruction=linear | Random | Grid | Wavelet |" in r.output
    assert "| reconstruction=shading | Random | Grid | Wavelet |" in r.output
    assert f"figures: {out / 'figures'}" in r.output
    with (out / "results.csv").open() as f:
        both = list(csv.DictReader(f))
    assert len(both) == 3 * 3 * 2 * 2 * 2
    rows = [row for row in both if row["reconstruction"] == "linear"]
    assert len(rows) == 3 * 3 * 2 * 2
    assert {row["strategy"] for row in rows} == {"random", "grid", "wavelet"}
    # k = round(density * N) of the 62 x 100 grid
    n = 62 * 100
    assert {(float(row["density"]), int(row["k"])) for row in rows} == {
        (0.25, round(n / 4)),
        (1 / 16, round(n / 16)),
        (1 / 64, round(n / 64)),
    }
    assert all(float(row["value"]) > 0 for row in rows)
    scores = (out / "scores.md").read_text()
    # eq. 4.3 recomputed from results.csv: trial-mean errors, ratio to random, 1/density weights
    for metric, name in (("mse", "MSE"), ("grad", "GRAD")):
        err = {}
        for row in rows:
            if row["metric"] == metric:
                key = (row["strategy"], float(row["density"]))
                err.setdefault(key, []).append(float(row["value"]))
        dens = sorted({d for _, d in err})
        w = np.array([1 / d for d in dens])
        want = [
            np.sum(w * [np.mean(err["random", d]) / np.mean(err[s, d]) for d in dens]) / w.sum()
            for s in ("random", "grid", "wavelet")
        ]
        line = next(x for x in scores.splitlines() if x.startswith(f"| {name} |"))
        cells = [v.strip(" *") for v in line.strip("|").split("|")[1:]]  # best in bold
        assert all(re.fullmatch(r"\d+\.\d\d \[\d+\.\d\d, \d+\.\d\d\]", c) for c in cells), cells
        got = [float(c.split()[0]) for c in cells]  # the point score before its interval
        np.testing.assert_allclose(got, want, atol=0.0051)
        assert got[0] == 1.0
        assert abs(got[2] - got[0]) > 0.01  # wavelet is not random in disguise
    assert "samples saved vs Random at equal MSE" in scores
    assert "samples saved vs linear at equal MSE, paired by seed" in scores
    assert (out / "reconstructions.csv").is_file() and (out / "samples_saved.csv").is_file()
    assert "| Grid |" in scores.split("samples saved vs Random")[1]
    assert "\\begin{tabular}{lrrr}" in (out / "scores.tex").read_text()
    prov = json.loads((out / "provenance.json").read_text())
    assert prov["variant"] in ("llvm_ad_rgb", "scalar_rgb", "cuda_ad_rgb")
    assert set(prov["timings"]["units"][prov["unit_keys"][0]]) >= {"render_s", "study_s"}
    figs = {p.name for p in (out / "figures").iterdir()}
    assert {"error_vs_density_mse.png", "panels_unit0.png"} <= figs
    assert not any(n.endswith(".pdf") for n in figs)  # PDF only on request (--pdf)
    assert "sparse_mesh_unit0.png" in figs  # Fig. 4
    assert "samples_saved.png" in figs
    from simlunar.results.store import UnitCache

    arr = UnitCache(out).load_arrays(prov["unit_keys"][0])
    # quickstart is Oren-Nayar: constant and energy-modulated renders of the sparse mesh
    assert arr["sparse_mesh_render_rough"].shape == arr["sparse_mesh_render"].shape
    sigma = arr["sparse_mesh_sigma"]
    assert np.radians(20) - 1e-6 <= sigma.min() and sigma.max() <= np.radians(45) + 1e-6

    # rerun: cached, identical; a fresh folder with the same seed: byte-identical
    r2 = run_cli(QUICKSTART, "--out", str(out), *SMALL, "--no-figures")
    assert "units: 1 (1 cached, 0 computed)" in r2.output
    run_cli(QUICKSTART, "--out", str(tmp_path / "again"), *SMALL, "--no-figures")
    assert (out / "results.csv").read_bytes() == (tmp_path / "again" / "results.csv").read_bytes()

    # `simlunar figures` redraws from the folder alone, PDF on request
    r3 = CliRunner().invoke(app, ["figures", str(out), "--pdf"])
    assert r3.exit_code == 0 and "panels_unit0.pdf" in r3.output


def _finished(units: Path) -> list[Path]:
    """Finished unit records; a hidden ``.<name>.tmp.json`` is a write the kill cut short."""
    return [p for p in units.glob("*.json") if not p.name.startswith(".")]


@pytest.mark.slow
def test_real_sweep_sigkill_then_resume(tmp_path):
    args = [*SMALL, "--set", "sweep={render.light.elevation_deg: [10, 40, 70]}", "--no-figures"]
    ref = tmp_path / "ref"
    run_cli(QUICKSTART, "--out", str(ref), *args)
    out = tmp_path / "killed"
    # the real CLI and units; the second unit waits at a gate that never opens (tests/pipeline/
    # fake_cli.py), so the kill comes after exactly one unit whatever the machine's load
    calls = tmp_path / "calls"
    env = {
        **os.environ,
        "SIMLUNAR_TEST_REAL_UNITS": "1",
        "SIMLUNAR_TEST_CALLS": str(calls),
        "SIMLUNAR_TEST_GATE": str(tmp_path / "never"),
        "SIMLUNAR_TEST_GATE_AFTER": "1",
    }
    fake_cli = Path(__file__).resolve().parent / "fake_cli.py"
    proc = subprocess.Popen(
        [sys.executable, str(fake_cli), "run", QUICKSTART, "--out", str(out), "--no-progress",
         *args],
        cwd=ROOT,
        env=env,
        start_new_session=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )  # fmt: skip
    deadline = time.monotonic() + 240
    units = out / "units"
    while time.monotonic() < deadline and proc.poll() is None:
        n_calls = len(list(calls.glob("*.call"))) if calls.is_dir() else 0
        if units.is_dir() and _finished(units) and n_calls >= 2:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be killed"
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = {p.name: p.stat().st_mtime_ns for p in _finished(units)}
    assert len(done) == 1
    r = run_cli(QUICKSTART, "--out", str(out), *args)
    assert f"units: 3 ({len(done)} cached, {3 - len(done)} computed)" in r.output
    assert {p.name: p.stat().st_mtime_ns for p in units.glob("*.json") if p.name in done} == done
    assert (out / "results.csv").read_bytes() == (ref / "results.csv").read_bytes()


@pytest.mark.slow
def test_scanner_experiment_end_to_end(tmp_path):
    out = tmp_path / "scan"
    r = run_cli(
        str(ROOT / "experiments" / "scanner_ambiguity.yaml"),
        "--out",
        str(out),
        "--set",
        "terrain.scale=0.125",
        "--set",
        "study.projector_px=[128, 96]",
        "--set",
        "study.camera_px=[128, 96]",
        "--set",
        "render.spp=4",
        "--set",
        "study.planners=[wavelet]",
        "--set",
        "study.metrics=[mse]",
        "--set",
        "sweep={}",
    )
    assert "| Gray code |" in r.output and "| Ambiguity enhancement / Wavelet |" in r.output
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert {row["mode"] for row in rows} == {"gray_code", "ambiguity_enhancement"}
    # 7 column bits + 7 row bits for a 128 x 96 projector, MSB first
    assert sum(row["metric"].startswith("ber_") for row in rows) == 14
    figs = {p.name for p in (out / "figures").iterdir()}
    assert "scanner_errors.png" in figs
    # the bit-error figure is drawn only when some bit was decoded wrongly (with its caption);
    # else not_drawn.md (and the report) says why there is none
    ber = [float(row["value"]) for row in rows if row["metric"].startswith("ber_")]
    drawn = any(v > 0 for v in ber)
    assert ("gray_code_bit_errors.png" in figs) == drawn
    notes = out / "figures" / ("captions.md" if drawn else "not_drawn.md")
    assert "## gray_code_bit_errors" in notes.read_text()


@pytest.mark.slow
def test_daylight_scan_ablation_reports_the_sun_to_projector_ratio(tmp_path):
    # study.scan_light: sun through the CLI: the gray-code rows carry ambient_ratio, linear in
    # the sun's irradiance (the sun's image is rendered with the same samples at every point)
    out = tmp_path / "day"
    run_cli(
        str(ROOT / "experiments" / "ablation_scanner_daylight.yaml"),
        "--out",
        str(out),
        "--set",
        "terrain.scale=0.125",
        "--set",
        "study.projector_px=[64, 48]",
        "--set",
        "study.camera_px=[96, 72]",
        "--set",
        "render.spp=4",
        "--set",
        "study.modes=[gray_code]",
        "--set",
        "study.metrics=[mse]",
        "--set",
        "sweep={render.light.irradiance: [0.01, 100]}",
    )
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    ratio = {r["unit"]: float(r["value"]) for r in rows if r["metric"] == "ambient_ratio"}
    assert set(ratio) == {"0", "1"} and ratio["0"] > 0
    assert ratio["1"] / ratio["0"] == pytest.approx(1e4, rel=1e-4)
    valid = {r["unit"]: float(r["value"]) for r in rows if r["metric"] == "valid_fraction"}
    assert valid["1"] < valid["0"]  # a sun 1e4x brighter drowns stripes
    # an ablation's figure plots the errors against the swept value; no bars pooled across it
    figs = {p.name for p in (out / "figures").iterdir()}
    assert "scanner_vs_irradiance.png" in figs and "scanner_errors.png" not in figs


@pytest.mark.slow
def test_real_sweep_on_dask_through_the_cli_matches_the_local_pool(tmp_path):
    import distributed

    args = [*SMALL, "--set", "sweep={render.light.elevation_deg: [15, 60]}", "--no-figures"]
    run_cli(QUICKSTART, "--out", str(tmp_path / "pool"), "--workers", "2", *args)
    # one worker thread: Mitsuba renders one scene at a time inside the worker
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        r = run_cli(
            QUICKSTART,
            "--out",
            str(tmp_path / "dask"),
            "--scheduler",
            cluster.scheduler_address,
            *args,
        )
    assert "units: 2 (0 cached, 2 computed)" in r.output
    assert (tmp_path / "pool" / "results.csv").read_bytes() == (
        tmp_path / "dask" / "results.csv"
    ).read_bytes()
    prov = json.loads((tmp_path / "dask" / "provenance.json").read_text())
    assert prov["executor"] == {"executor": "dask", "scheduler": cluster.scheduler_address}


@pytest.mark.slow
def test_the_quickstart_itself_runs(tmp_path):
    """`make run` runs exactly this file: 1 unit, 9 strategies x 7 densities x 3 trials x 3
    metrics x 2 reconstructions (linear, shading); its samples-saved tables show the oracle, the Lloyd layouts and the recommended
    image-directed planner (wavelet + Lloyd) not losing to the grid."""
    out = tmp_path / "quickstart"
    r = run_cli(QUICKSTART, "--out", str(out), "--no-figures")
    header = (
        "| reconstruction=linear | Random | Grid | Gradient | Entropy | Wavelet | Uniform Lloyd |"
        " Wavelet, Lloyd |"
        " Sequential, wavelet prior | Oracle greedy (true error) |"
    )
    assert header in r.output
    assert "| MSE | 1.00 [1.00, 1.00] |" in r.output
    assert "samples saved vs Random at equal MSE" in r.output
    assert "samples saved vs Uniform Lloyd at equal MSE" in r.output
    assert "headroom captured vs Oracle greedy (true error)" in r.output
    grid = r.output.split("samples saved vs Grid at equal MSE\n")[1].split("###")[0]
    assert "| Oracle greedy (true error) |" in grid and "| Uniform Lloyd |" in grid
    row = next(line for line in grid.splitlines() if line.startswith("| Wavelet, Lloyd |"))
    geo_mean = float(row.split("|")[-2].split()[0])
    assert geo_mean >= 1.0  # measured 1.24 (seed 1)
    with (out / "results.csv").open() as f:
        assert sum(1 for _ in f) == 1 + 9 * 7 * 3 * 3 * 2
    assert "samples saved vs linear at equal MSE, paired by seed" in r.output


@pytest.mark.slow
def test_the_docs_set_example_without_random_still_gives_the_vs_grid_table(tmp_path):
    # docs/experiments.md's first --set example (less its spp, shrunk as SMALL): the score
    # table was all "-", scores.csv empty, the samples-saved table dropped, nothing said why
    out = tmp_path / "qs"
    pairs = [SMALL[i : i + 2] for i in range(0, len(SMALL), 2)]
    small = [a for p in pairs if not p[1].startswith("study.strategies") for a in p]
    r = run_cli(QUICKSTART, "--out", str(out), *small, "--set", "study.strategies=[grid, wavelet]")
    assert "relative to the random strategy" in r.output and "add random" in r.output
    assert "| –" not in r.output
    md = (out / "scores.md").read_text()
    table = md.split("samples saved vs Grid at equal MSE")[1]
    assert re.search(r"\| Wavelet \| \d", table)
    assert not (out / "scores.csv").exists() and "no scores.csv" in md
    figs = {p.name for p in (out / "figures").iterdir()}
    assert {"samples_saved.png", "error_vs_density_mse.png"} <= figs
