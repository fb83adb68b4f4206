"""`simlunar <command> ... | head -1`: a reader that closes stdout never kills a command; the
command finishes its work (the files it writes, the report of a run) and stops printing, and
exits as it would have (0). One subprocess per command, its stdout a pipe closed before the
first line (every write the command makes finds it closed, so no timing decides the outcome);
a structural test keeps every command's stdout lines on the one helper that allows this."""

from __future__ import annotations

import ast
import csv
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
TINY = ["--set", "study.strategies=[random]", "--set", "study.trials=1",
        "--set", "study.densities=[1/16]", "--set", "terrain.scale=0.05",
        "--set", "sweep={render.light.elevation_deg: [20, 40]}"]  # fmt: skip


def _closed_stdout(args, tmp_path, *, python=("-m", "simlunar.cli")):
    """Run ``simlunar args`` with its stdout a pipe whose reader went away before the first
    line (``| head -0``): (exit code, stderr)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    with open(tmp_path / "stderr", "w") as err:
        proc = subprocess.Popen(
            [sys.executable, *python, *args],
            cwd=ROOT, stdout=subprocess.PIPE, stderr=err, env=env,
        )  # fmt: skip
        proc.stdout.close()
        rc = proc.wait(timeout=600)
    return rc, (tmp_path / "stderr").read_text()


def _quiet(err: str) -> bool:
    return "Traceback" not in err and "error" not in err


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    """A tiny two-unit run of the quickstart experiment, its stdout closed: (rc, stderr, folder)."""
    tmp = tmp_path_factory.mktemp("closed")
    out = tmp / "out"
    rc, err = _closed_stdout(
        ["run", "experiments/quickstart.yaml", "--out", str(out), "--no-progress",
         "--no-figures", *TINY], tmp)  # fmt: skip
    return rc, err, out


@pytest.mark.slow
def test_a_run_whose_reader_closed_stdout_finishes_its_work(finished_run):
    rc, err, out = finished_run
    # before: exit 141 at the first line of the summary, report.html never written
    assert rc == 0, err
    assert _quiet(err)
    assert (out / "report.html").is_file() and (out / "provenance.json").is_file()
    rows = list(csv.DictReader((out / "results.csv").read_text().splitlines()))
    assert {r["unit"] for r in rows} == {"0", "1"}


def test_a_dry_run_whose_reader_closed_stdout_exits_quietly(tmp_path):
    rc, err = _closed_stdout(
        ["run", "experiments/quickstart.yaml", "--out", str(tmp_path / "o"), "--dry-run", *TINY],
        tmp_path,
    )
    assert rc == 0, err
    assert "Traceback" not in err
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_figures_of_a_folder_drawn_with_stdout_closed(finished_run, tmp_path):
    folder = tmp_path / "copy"
    shutil.copytree(finished_run[2], folder)  # the run drew no figures (--no-figures)
    rc, err = _closed_stdout(["figures", str(folder)], tmp_path)
    # before: exit 141 at "redrew N file(s)", after the figures were drawn
    assert rc == 0, err
    assert _quiet(err)
    assert list((folder / "figures").glob("*.png"))


def test_report_of_a_folder_written_with_stdout_closed(finished_run, tmp_path):
    folder = tmp_path / "copy"
    shutil.copytree(finished_run[2], folder)
    (folder / "report.html").unlink()
    rc, err = _closed_stdout(["report", str(folder)], tmp_path)
    # before: exit 141 at the line naming the page
    assert rc == 0, err
    assert _quiet(err)
    assert (folder / "report.html").is_file()


def test_a_terrain_generated_with_stdout_closed_writes_every_file(tmp_path):
    out = tmp_path / "t"
    rc, err = _closed_stdout(
        ["terrain", "aerial_3", "--out", str(out), "--scale", "0.05", "--stats"], tmp_path
    )
    # before: exit 141 at the first line ("aerial_3: 50 x 80 cells ..."), before any file
    assert rc == 0, err
    assert _quiet(err)
    assert {"dem.exr", "albedo.png", "hillshade.png", "mesh.ply", "features.json"} <= {
        p.name for p in out.iterdir()
    }


def test_terrain_stats_of_a_dem_with_stdout_closed_exits_0(tmp_path):
    from simlunar.terrain import Terrain, io

    heights = 0.02 * np.random.default_rng(0).standard_normal((40, 50))
    io.save_dem(
        tmp_path / "dem.npz",
        Terrain(heights=heights, albedo=np.full((40, 50), 0.12, np.float32), spacing=0.5),
    )
    rc, err = _closed_stdout(["terrain", str(tmp_path / "dem.npz"), "--stats"], tmp_path)
    assert rc == 0, err
    assert _quiet(err)


@pytest.mark.slow
@pytest.mark.render
def test_a_scene_rendered_with_stdout_closed_writes_every_file(tmp_path):
    (tmp_path / "scene.yaml").write_text(
        "name: tiny\nterrain: {preset: aerial_1, scale: 0.05}\nrender: {spp: 1}\n"
    )
    out = tmp_path / "r"
    rc, err = _closed_stdout(["render", str(tmp_path / "scene.yaml"), "--out", str(out)], tmp_path)
    # before: exit 141 at the first line listing the files
    assert rc == 0, err
    assert _quiet(err)
    assert {"radiance.exr", "preview.png", "ground_truth.npz", "scene.json"} <= {
        p.name for p in out.iterdir()
    }


#: ``simlunar train`` with the views replaced by a planted relation (no render): the
#: training, the model file and its record are real
_TRAIN = textwrap.dedent(
    """
    import sys
    import numpy as np
    from simlunar.pipeline import train

    def view(cfg, *, with_guide=False):
        rng = np.random.default_rng(cfg.terrain.seed_index)
        bright = np.zeros((32, 40))
        bright[8:20, 10:30] = 1.0
        depth = 0.01 * np.arange(40)[None, :] + bright * rng.normal(0, 0.5, (32, 40))
        return (0.2 + 0.6 * bright).astype(np.float32), depth

    train.guide_view = view
    from simlunar.cli import main
    sys.argv = ["simlunar", *sys.argv[1:]]
    main()
    """
)


@pytest.mark.slow
def test_a_model_trained_with_stdout_closed_is_written(tmp_path):
    import yaml

    model = tmp_path / "models" / "tiny.joblib"
    cfg = {
        "name": "tiny", "seed": 100, "scale": 0.25,
        "experiments": [str(ROOT / "experiments" / "table1_aerial.yaml")],
        "held_out_presets": ["aerial_2"], "terrain_seeds": 1, "sun_elevations_deg": [30],
        "densities": ["1/16"], "model": str(model),
        "options": {"layouts": 1, "pixels_per_example": 200, "max_iter": 5},
    }  # fmt: skip
    (tmp_path / "train.yaml").write_text(yaml.safe_dump(cfg))
    rc, err = _closed_stdout(["train", str(tmp_path / "train.yaml")], tmp_path,
                             python=("-c", _TRAIN))  # fmt: skip
    # before: exit 141 at the first progress line ("rendered 1/2 ..."), no model written
    assert rc == 0, err
    assert _quiet(err)
    assert model.is_file() and model.with_suffix(".json").is_file()


@pytest.mark.parametrize(
    "args",
    [
        ["schema"],
        ["schema", "--markdown"],
        ["doctor"],
        ["doctor", "--short"],
        ["--version"],
    ],
    ids=" ".join,
)
def test_a_command_whose_output_is_its_work_exits_0_with_stdout_closed(args, tmp_path):
    rc, err = _closed_stdout(args, tmp_path)
    # before: 141 (the reader went away; nothing was left undone but the printing)
    assert rc == 0, err
    assert err == ""


def test_every_command_prints_to_stdout_through_the_helper_that_survives_a_closed_pipe():
    """A ``typer.echo``/``print`` to stdout in a command module would end the command at the
    first line a closed pipe refuses (exit 141, the work after it never done)."""
    found = []
    for path in sorted((ROOT / "simlunar" / "cli").glob("*.py")):
        if path.name == "common.py":  # the helper itself
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.Call):
                continue
            f = node.func
            name = (
                f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else ""
            )
            to_err = any(
                k.arg == "err" and isinstance(k.value, ast.Constant) and k.value.value is True
                for k in node.keywords
            )
            if name in ("print", "secho") or (
                isinstance(f, ast.Attribute) and name == "echo" and not to_err
            ):
                found.append(f"{path.name}:{node.lineno}")
            # a stdout writer handed to the library (log=typer.echo)
            found += [
                f"{path.name}:{node.lineno}"
                for k in node.keywords
                if isinstance(k.value, ast.Attribute) and k.value.attr == "echo"
            ]
    assert found == []
