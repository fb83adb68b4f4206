"""CLI `run`, `schema`, `figures`: bad input gives one line, exit code 2, and writes nothing."""

from __future__ import annotations

import json
import time

import pytest
import yaml
from typer.testing import CliRunner

from simlunar.cli import app

GOOD = {
    "name": "cli_test",
    "seed": 1,
    "terrain": {"preset": "aerial_1", "scale": 0.125},
    "study": {
        "strategies": ["random", "wavelet"],
        "densities": ["1/2", "1/8"],
        "trials": 2,
        "metrics": ["mse"],
    },
}


def invoke(*args):
    return CliRunner().invoke(app, list(args))


def write(tmp_path, data) -> str:
    p = tmp_path / "exp.yaml"
    p.write_text(yaml.safe_dump(data) if not isinstance(data, str) else data)
    return str(p)


def _with(path: str, value):
    from simlunar.config.loading import set_path

    return set_path(GOOD, path, value)


BAD = [
    (
        "unknown key",
        _with("render.light.elevation_rad", 0.3),
        "render.light.elevation_rad: unknown key",
    ),
    (
        "wrong type",
        _with("study.trials", "twenty"),
        "study.trials: Input should be a valid integer",
    ),
    (
        "bad unit",
        _with("render.light.elevation_deg", "30 parsec"),
        "render.light.elevation_deg: bad unit 'parsec'",
    ),
    (
        "sweep over a missing key",
        {**GOOD, "sweep": {"render.light.zenith_deg": [1, 2]}},
        "sweep.render.light.zenith_deg: no such key",
    ),
    (
        "missing file",
        {**GOOD, "terrain": {"file": "no_such_dem.npy", "spacing_m": 0.2}},
        "terrain.file: file not found",
    ),
]
BAD_REGISTRY = [
    (
        "unknown preset",
        _with("terrain.preset", "aerial_9"),
        "terrain.preset: unknown terrain preset 'aerial_9'",
    ),
    (
        "unknown strategy",
        _with("study.strategies", ["random", "wavelets"]),
        "study.strategies[1]: unknown strategy 'wavelets'",
    ),
]


def _check_one_line_error(result, expected: str, yaml_path: str, out) -> None:
    assert result.exit_code == 2, result.output
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert len(lines) == 1, result.output
    where = f"{yaml_path}: " if yaml_path else ""
    assert lines[0].startswith(f"error: {where}{expected}"), lines[0]
    assert "Traceback" not in result.output
    assert not out.exists()


@pytest.mark.parametrize(("case", "data", "expected"), BAD, ids=[b[0] for b in BAD])
def test_bad_config_is_one_line_exit_2_nothing_written(case, data, expected, tmp_path):
    path = write(tmp_path, data)
    out = tmp_path / "results"
    _check_one_line_error(invoke("run", path, "--out", str(out)), expected, path, out)


@pytest.mark.parametrize(
    ("case", "data", "expected"), BAD_REGISTRY, ids=[b[0] for b in BAD_REGISTRY]
)
def test_unknown_names_are_one_line_exit_2(case, data, expected, tmp_path):
    path = write(tmp_path, data)
    out = tmp_path / "results"
    _check_one_line_error(invoke("run", path, "--out", str(out)), expected, path, out)


def test_missing_yaml_and_bad_set_and_bad_scheduler(tmp_path):
    out = tmp_path / "results"
    r = invoke("run", str(tmp_path / "nope.yaml"), "--out", str(out))
    assert r.exit_code == 2 and "error: experiment file not found" in r.output
    path = write(tmp_path, GOOD)
    r = invoke("run", path, "--out", str(out), "--set", "render.spq=3")
    # the mistake is on the command line: the error names the --set, not the file
    _check_one_line_error(r, "--set render.spq: no such key", "", out)
    r = invoke("run", path, "--out", str(out), "--set", "render.spp=0")
    _check_one_line_error(
        r, "--set render.spp: Input should be greater than or equal to 1", "", out
    )


def test_unreachable_scheduler_writes_nothing(tmp_path):
    path = write(tmp_path, GOOD)
    out = tmp_path / "results"
    t0 = time.perf_counter()
    r = invoke("run", path, "--out", str(out), "--scheduler", "tcp://127.0.0.1:9")
    assert r.exit_code == 2, r.output
    assert r.output.startswith("error: --scheduler tcp://127.0.0.1:9: cannot connect")
    assert len(r.output.strip().splitlines()) == 1
    assert not out.exists()
    # a closed port fails at once, not after Dask's retries; generous for a busy CI machine
    assert time.perf_counter() - t0 < 60


def test_schema_command(tmp_path):
    r = invoke("schema")
    assert r.exit_code == 0
    s = json.loads(r.output)
    assert s["title"] == "simlunar experiment"
    out = tmp_path / "schema.json"
    assert invoke("schema", "--out", str(out)).exit_code == 0
    assert json.loads(out.read_text()) == s


def test_figures_on_a_non_result_folder(tmp_path):
    r = invoke("figures", str(tmp_path))
    assert r.exit_code == 2
    assert "not a result folder (missing config.yaml)" in r.output


# --------------------------------------------------------------------------- terrain, render
def _one_error_line(r, expect: str) -> None:
    assert r.exit_code == 2, r.output
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and expect in lines[0], r.stderr
    assert "Traceback" not in r.output


@pytest.mark.parametrize(
    ("args", "expect"),
    [
        (("terrain", "aerial_9", "--out", "{d}/t"), "unknown terrain preset 'aerial_9'"),
        (("terrain", "aerial_1", "--out", "{d}/t", "--scale", "0"), "scale"),
        (("terrain", "aerial_1", "--out", "{d}/t", "--format", "bmp"), "--format must be"),
        (("terrain", "aerial_1", "--out", "{d}/file"), "is a file, not a folder"),
        (("terrain", "aerial_1", "--out", "{d}/file/t"), "is a file, so no folder can be made"),
        (("render", "{d}/nope.yaml", "--out", "{d}/r"), "scene file not found"),
        (("render", "{d}/scene.yaml", "--out", "{d}/file"), "is a file, not a folder"),
        (("render", "{d}/bad_dem_scene.yaml", "--out", "{d}/r"), "every height is NaN"),
        (("render", "{d}/away_scene.yaml", "--out", "{d}/r"), "render.camera: the camera at"),
        (("figures", "{d}/file"), "is a file, not a folder"),
        (("figures", "{d}/nothing"), "no such folder"),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, tuple) else None,
)
def test_terrain_render_figures_file_errors_are_one_line(args, expect, tmp_path):
    import numpy as np

    (tmp_path / "file").write_text("x")
    (tmp_path / "scene.yaml").write_text("terrain: {preset: aerial_1, scale: 0.125}\n")
    np.save(tmp_path / "nan.npy", np.full((8, 8), np.nan))
    (tmp_path / "bad_dem_scene.yaml").write_text("terrain: {file: nan.npy, spacing_m: 0.2}\n")
    (tmp_path / "away_scene.yaml").write_text(
        "terrain: {preset: aerial_1, scale: 0.125}\nrender: {camera: {kind: perspective, "
        "width: 32, height: 24, fov_deg: 30, position_m: [0, 0, 60], look_at_m: [0, 0, 90]}}\n"
    )
    before = sorted((p.name, p.stat().st_size) for p in tmp_path.rglob("*"))
    r = invoke(*[a.format(d=tmp_path) for a in args])
    _one_error_line(r, expect)
    assert sorted((p.name, p.stat().st_size) for p in tmp_path.rglob("*")) == before


# --------------------------------------------------------------------------- first contact
def test_run_help_shows_the_defaults_and_the_flag_pairs():
    r = CliRunner().invoke(app, ["run", "--help"], terminal_width=200)
    assert r.exit_code == 0, r.output
    assert "[default: results/<name>]" in r.output
    assert "[default: 1]" in r.output  # --workers
    assert "--figures / --no-figures" in r.output
    assert "--progress / --no-progress" in r.output
    assert "<bool>" not in r.output  # a flag takes no value


def test_the_command_list_shows_each_commands_own_help_line():
    # `simlunar --help` lists the lines of simlunar.cli.COMMANDS without importing a command
    import typer

    from simlunar.cli import COMMANDS

    group = typer.main.get_command(app)
    ctx = typer.Context(group)
    assert group.list_commands(ctx) == list(COMMANDS)
    for name, (_, line) in COMMANDS.items():
        assert group.get_command(ctx, name).help.strip() == line, name


def test_help_and_version_import_no_command(tmp_path):
    import subprocess
    import sys

    probe = (
        "import sys, runpy; sys.argv = ['simlunar', *sys.argv[1:]]\n"
        "try:\n    runpy.run_module('simlunar.cli', run_name='__main__')\n"
        "except SystemExit:\n    pass\n"
        "loaded = sorted(m for m in sys.modules if m.startswith('simlunar.') and m not in "
        "('simlunar.cli', 'simlunar.cli.common', 'simlunar.cli.__main__', 'simlunar.errors', "
        "'simlunar.interrupts'))\n"
        "print('LOADED', loaded)\n"
    )
    for args in (["--help"], ["--version"], []):
        r = subprocess.run(
            [sys.executable, "-c", probe, *args], capture_output=True, text=True, check=False
        )
        assert "LOADED []" in r.stdout, (args, r.stdout, r.stderr)


@pytest.mark.parametrize(
    "command", ["run", "figures", "render", "terrain", "schema", "doctor", "train"]
)
def test_a_commands_help_imports_only_its_command_module(command):
    # `simlunar run --help` took 3.6 s when the command modules imported the library at their
    # top (config.registry reads every planner, sensor and renderer); the help needs Typer and
    # the command's signature only
    import subprocess
    import sys

    probe = (
        "import sys, runpy; sys.argv = ['simlunar', *sys.argv[1:]]\n"
        "try:\n    runpy.run_module('simlunar.cli', run_name='__main__')\n"
        "except SystemExit:\n    pass\n"
        "print('LOADED', sorted(m for m in sys.modules if m.startswith('simlunar.') and not "
        "m.startswith('simlunar.cli') and m not in ('simlunar.errors', 'simlunar.interrupts', "
        "'simlunar.config', 'simlunar.config.yamlio', 'simlunar.pipeline', "
        "'simlunar.pipeline.executors')))\n"
        "print('NUMPY', 'numpy' in sys.modules)\n"
    )
    r = subprocess.run(
        [sys.executable, "-c", probe, command, "--help"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert "Usage:" in r.stdout, r.stderr
    assert "LOADED []" in r.stdout and "NUMPY False" in r.stdout, (r.stdout, r.stderr)


def test_version():
    import simlunar

    r = invoke("--version")
    assert r.exit_code == 0, r.output
    assert r.output.strip() == f"simlunar {simlunar.__version__}"


@pytest.mark.parametrize("flag", ["--figures", "--no-figures"])
def test_figure_flags_take_no_value(flag, tmp_path):
    # before, `--no-figures` showed as `--no-figures <bool>` and `--no-figures true` failed;
    # a bad scheduler stops the run before anything is computed, after the options parsed
    r = invoke("run", write(tmp_path, GOOD), flag, "--scheduler", "nope://x", "--no-progress")
    assert "No such option" not in r.output
    assert r.exit_code == 2


def test_render_refuses_a_folder_that_is_not_a_render_folder(tmp_path):
    scene = tmp_path / "scene.yaml"
    scene.write_text("terrain: {preset: aerial_1, scale: 0.125}\n")
    experiment = tmp_path / "exp_folder"  # a result folder of `simlunar run`
    experiment.mkdir()
    (experiment / "config.yaml").write_text("name: x\n")
    (experiment / "results.csv").write_text("unit,metric,value\n")
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine\n")
    for folder, expect in (
        (experiment, "not empty and an experiment's result folder"),
        (other, "not empty and not a render folder (no scene.json, found notes.txt)"),
    ):
        before = sorted(p.name for p in folder.iterdir())
        r = invoke("render", str(scene), "--out", str(folder))
        _one_error_line(r, expect)
        assert sorted(p.name for p in folder.iterdir()) == before
