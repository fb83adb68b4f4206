"""A tiny lidar experiment end to end through `simlunar run`: results.csv carries scan time."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest
from typer.testing import CliRunner

from simlunar.cli import app

pytestmark = [pytest.mark.render, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]
TINY = [
    "--set",
    "terrain.overrides.grid={rows: 80, cols: 80}",
    "--set",
    "render.camera.position_m=[8.0, -8.0, 20.0]",
    "--set",
    "render.camera.look_at_m=[8.0, -8.0, 0.0]",
    "--set",
    "render.camera.width=32",
    "--set",
    "render.camera.height=32",
    "--set",
    "render.spp=4",
    "--set",
    "study.planners=[random, grid]",
    "--set",
    "study.planner_opts={}",
    "--set",
    "study.densities=[1/8, 1/32]",
    "--set",
    "study.trials=1",
    "--set",
    "study.terrain_seeds=1",
]


def test_a_tiny_steered_beam_study_runs_end_to_end(tmp_path):
    out = tmp_path / "lidar"
    args = ["run", str(ROOT / "experiments" / "lidar_descent_altimeter.yaml"), "--out", str(out)]
    r = CliRunner().invoke(app, [*args, *TINY, "--no-progress"])
    assert r.exit_code == 0, r.output
    assert "| Planner | k | samples | scan time (s) | MSE | GRAD | valid fraction |" in r.output
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert {"planner", "k", "seconds", "frames", "samples", "value"} <= set(rows[0])
    assert len(rows) == 2 * 2 * 3  # planners x densities x (mse, grad, valid_fraction)
    assert {r["k"] for r in rows} == {"128", "32"}
    for row in rows:
        # 4 pulses per point; a scan of more points takes longer
        assert float(row["seconds"]) > 0 and int(row["frames"]) == 4 * int(row["k"])
    by_k = {int(r["k"]): float(r["seconds"]) for r in rows if r["planner"] == "grid"}
    assert by_k[128] > by_k[32]
    figs = {p.name for p in (out / "figures").iterdir()}
    assert {"lidar_error_vs_time_mse.png", "lidar_error_vs_samples_grad.png"} <= figs
    # the picture of the scan: guide image, beams in visiting order, measured depths
    assert "lidar_scan_unit0.png" in figs
    assert "## lidar_scan_unit0" in (out / "figures" / "captions.md").read_text()


def test_save_scans_writes_las_files_laspy_reads(tmp_path):
    import json

    import laspy
    import numpy as np

    out = tmp_path / "lidar"
    args = ["run", str(ROOT / "experiments" / "lidar_descent_altimeter.yaml"), "--out", str(out)]
    tiny = [*TINY, "--set", "study.planners=[grid]", "--set", "study.densities=[1/16]"]
    r = CliRunner().invoke(app, [*args, *tiny, "--no-progress", "--save-scans", "--save-arrays"])
    assert r.exit_code == 0, r.output
    folder = out / "scans" / "unit0"
    manifest = json.loads((folder / "manifest.json").read_text())
    las = laspy.read(folder / "grid.laz")
    assert len(las.points) == manifest["points"]["grid"] > 0
    # the points lie on the terrain below the 20 m high sensor, in the guide view's patch
    z = np.asarray(las.z)
    assert np.abs(z).max() < 3.0
    assert np.asarray(las.time_from_start).max() <= manifest["seconds"]["grid"]
    assert (folder / "grid.ply").is_file() and (folder / "grid_range.exr").is_file()
    # --save-arrays: a perspective view exports depth on the pixel grid, without a CRS
    arrays = json.loads((out / "arrays" / "unit0" / "manifest.json").read_text())
    assert arrays["quantity"] == "depth" and arrays["crs"] is None
    names = {f["tif"] for f in arrays["files"]}
    assert names == {"truth_depth.tif", "grid_1-16_linear_depth.tif", "grid_1-16_linear_error.tif"}


def test_a_lidar_study_scores_every_reconstruction_with_extra_guide_frames(tmp_path):
    out = tmp_path / "lidar"
    args = ["run", str(ROOT / "experiments" / "lidar_descent_altimeter.yaml"), "--out", str(out)]
    tiny = [*TINY, "--set", "study.planners=[grid]", "--set", "study.densities=[1/8]",
            "--set", "render.guide_frames=[camera]",
            "--set", "study.reconstructions=[linear, smoothed, shading]"]  # fmt: skip
    r = CliRunner().invoke(app, [*args, *tiny, "--no-progress"])
    assert r.exit_code == 0, r.output
    with (out / "results.csv").open() as f:
        rows = [row for row in csv.DictReader(f) if row["metric"] == "mse"]
    by = {row["reconstruction"]: row for row in rows}
    assert set(by) == {"linear", "smoothed", "shading"}
    assert all(float(row["value"]) > 0 for row in rows)
    assert by["linear"]["guide_frames"] == "" and by["smoothed"]["exposures"] == ""
    assert "camera" in by["shading"]["guide_frames"].split("+")
    assert int(by["shading"]["exposures"]) == len(by["shading"]["guide_frames"].split("+"))


@pytest.mark.parametrize("model", ["galvanometer", "continuous_raster"])
def test_a_descent_study_with_a_moving_platform_runs(tmp_path, model):
    # a 2 m/s descent with 1 m/s drift and 0.5 mrad of jitter, the pose known exactly: the
    # study runs, the cloud lands on the terrain (|z| < 3 m) and costs the model's time
    import json

    import laspy
    import numpy as np

    out = tmp_path / "lidar"
    args = ["run", str(ROOT / "experiments" / "lidar_descent_altimeter.yaml"), "--out", str(out)]
    motion = ("study.options.motion={kind: descent, descent_rate_m_s: 2.0, "
              "horizontal_m_s: [1.0, 0.0], attitude_jitter_urad: 500}")  # fmt: skip
    tiny = [*TINY, "--set", "study.planners=[grid]", "--set", "study.densities=[1/16]",
            "--set", motion, "--set", f"study.options.steered_beam.model={model}"]  # fmt: skip
    r = CliRunner().invoke(app, [*args, *tiny, "--no-progress", "--save-scans"])
    assert r.exit_code == 0, r.output
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert {r["metric"] for r in rows} >= {"mse", "valid_fraction"}
    mse = [float(r["value"]) for r in rows if r["metric"] == "mse"]
    assert 0 < mse[0] < 1.0  # a moving beam's depth in the guide view, within decimetres
    folder = out / "scans" / "unit0"
    manifest = json.loads((folder / "manifest.json").read_text())
    las = laspy.read(folder / "grid.laz")
    assert len(las.points) > 0 and np.abs(np.asarray(las.z)).max() < 3.0
    assert manifest["seconds"]["grid"] > 0


def test_a_descent_study_with_a_moving_micromirror_runs(tmp_path):
    # the micromirror experiment on the tiny scene, descending at 2 m/s with 1 m/s drift and
    # 0.5 mrad of jitter, the pose known exactly: each frame from its own pose, the cloud on
    # the terrain (|z| < 3 m: the tiny patch's relief) and the cost the frames' (4 pulses
    # at 30 Hz each); the same study placed from the start costs the same and scores worse
    import json

    import laspy
    import numpy as np

    def run(name, compensation):
        out = tmp_path / name
        args = ["run", str(ROOT / "experiments" / "lidar_descent_micromirror.yaml"),
                "--out", str(out)]  # fmt: skip
        motion = ("study.options.motion={kind: descent, descent_rate_m_s: 2.0, "
                  "horizontal_m_s: [1.0, 0.0], attitude_jitter_urad: 500, "
                  f"compensation: {compensation}}}")  # fmt: skip
        tiny = [*TINY, "--set", "study.planners=[random]", "--set", "study.densities=[1/16]",
                "--set", "study.options.micromirror={receiver_px: [8, 8]}",
                "--set", "study.options.transient={spp: 64}", "--set", motion]  # fmt: skip
        r = CliRunner().invoke(app, [*args, *tiny, "--no-progress", "--no-figures",
                                     "--save-scans"])  # fmt: skip
        assert r.exit_code == 0, r.output
        with (out / "results.csv").open() as f:
            return out, list(csv.DictReader(f))

    out, rows = run("exact", "exact")
    assert {r["metric"] for r in rows} >= {"mse", "valid_fraction"}
    frames = int(rows[0]["frames"])
    assert frames >= 2 and float(rows[0]["seconds"]) == pytest.approx(frames * 4 / 30.0)
    mse = next(float(r["value"]) for r in rows if r["metric"] == "mse")
    assert 0 < mse < 1.0
    folder = out / "scans" / "unit0"
    las = laspy.read(folder / "random.laz")
    assert len(las.points) > 0 and np.abs(np.asarray(las.z)).max() < 3.0
    assert json.loads((folder / "manifest.json").read_text())["seconds"]["random"] > 0
    _, start = run("start", "start")
    assert int(start[0]["frames"]) == frames
    assert next(float(r["value"]) for r in start if r["metric"] == "mse") > mse


def test_multi_round_planning_on_a_descending_platform_runs(tmp_path):
    # sequential on a 1 m/s descent (0.5 m/s drift, 0.5 mrad jitter, the pose known exactly)
    # with the altimeter on: each round continues the trajectory and ranges its datum from
    # where the platform is; the study runs, its row counts every round, the cloud lands on
    # the terrain (|z| < 3 m) and its points' times run on over the rounds
    import json

    import laspy
    import numpy as np

    out = tmp_path / "lidar"
    args = ["run", str(ROOT / "experiments" / "lidar_descent_altimeter.yaml"), "--out", str(out)]
    motion = ("study.options.motion={kind: descent, descent_rate_m_s: 1.0, "
              "horizontal_m_s: [0.5, 0.0], attitude_jitter_urad: 500}")  # fmt: skip
    tiny = [*TINY, "--set", "study.planners=[sequential]", "--set", "study.densities=[1/32]",
            "--set", motion, "--set", "study.options.gate.altimeter=true"]  # fmt: skip
    r = CliRunner().invoke(app, [*args, *tiny, "--no-progress", "--save-scans"])
    assert r.exit_code == 0, r.output
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    mse = [row for row in rows if row["metric"] == "mse"]
    assert len(mse) == 1 and 0 < float(mse[0]["value"]) < 1.0
    row = mse[0]
    assert int(row["rounds"]) >= 2 and int(row["samples"]) == int(row["k"]) == 32
    # 4 pulses per point plus the altimeter's steps before every round
    assert int(row["frames"]) >= 4 * (32 + int(row["rounds"]))
    folder = out / "scans" / "unit0"
    manifest = json.loads((folder / "manifest.json").read_text())
    las = laspy.read(folder / "sequential.laz")
    assert len(las.points) > 0 and np.abs(np.asarray(las.z)).max() < 3.0
    # the seconds from the acquisition's start (gps_time is 0: no absolute time is known)
    t = np.asarray(las.time_from_start)
    assert float(row["seconds"]) == pytest.approx(manifest["seconds"]["sequential"])
    assert 0.5 * manifest["seconds"]["sequential"] < t.max() <= manifest["seconds"]["sequential"]


def test_multi_round_planning_on_a_descending_micromirror_runs(tmp_path):
    # sequential through the moving micromirror on the tiny scene: the rounds continue one
    # trajectory (each round's first frame when the last ended), the row counts every round
    # and its frames, and its seconds are the frames' (the mirrors switch at once)
    out = tmp_path / "mm"
    args = ["run", str(ROOT / "experiments" / "lidar_descent_micromirror.yaml"), "--out", str(out)]
    motion = ("study.options.motion={kind: descent, descent_rate_m_s: 2.0, "
              "horizontal_m_s: [1.0, 0.0]}")  # fmt: skip
    tiny = [*TINY, "--set", "study.planners=[sequential]", "--set", "study.densities=[1/16]",
            "--set", "study.options.micromirror={receiver_px: [8, 8]}",
            "--set", "study.options.transient={spp: 64}", "--set", motion]  # fmt: skip
    r = CliRunner().invoke(app, [*args, *tiny, "--no-progress", "--no-figures"])
    assert r.exit_code == 0, r.output
    with (out / "results.csv").open() as f:
        rows = [row for row in csv.DictReader(f) if row["metric"] == "mse"]
    assert len(rows) == 1 and 0 < float(rows[0]["value"]) < 1.0
    row = rows[0]
    assert int(row["rounds"]) >= 2 and int(row["frames"]) >= int(row["rounds"])
    assert float(row["seconds"]) == pytest.approx(int(row["frames"]) * 4 / 30.0)
