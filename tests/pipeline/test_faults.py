"""Faults around a run: one run per folder, one config per folder, changed inputs, kills,
Ctrl-C, internal errors, and `simlunar figures` on damaged folders.

Work units are :mod:`fake_unit` (cheap, deterministic); subprocess runs go through the real
CLI with that unit (:mod:`fake_cli`), so exit codes and stderr are the user's.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from fake_unit import fake_unit
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.config.loading import load_experiment
from simlunar.errors import ResultFolderError
from simlunar.pipeline.runner import run_experiment
from simlunar.results.store import FolderLock

HERE = Path(__file__).resolve().parent
EXP = {
    "name": "faults",
    "seed": 3,
    "terrain": {"preset": "aerial_1", "scale": 0.125},
    "study": {
        "strategies": ["random", "grid", "wavelet"],
        "densities": ["1/2", "1/8"],
        "trials": 2,
        "metrics": ["mse", "grad"],
    },
    "sweep": {"render.light.elevation_deg": [10, 30, 50, 70]},
    "figures": {"enabled": False},
}


def write_exp(path: Path, data: dict) -> Path:
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def tree(root: Path, *, skip=("provenance.json", "report.html")) -> dict[str, str]:
    """Relative path -> SHA-256 of every file under ``root`` (``skip``: names with timings;
    report.html is written by the command, not by the pipeline)."""
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file() and p.name not in skip
    }


def cli(*args, env=None, **kw) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, str(HERE / "fake_cli.py"), *args],
        env={**os.environ, **(env or {})},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        **kw,
    )


def run_fake(exp: Path, out: Path):
    cfg = load_experiment(exp)
    return run_experiment(cfg, out, compute=fake_unit, progress=False, figures=False)


def wait_for(cond, timeout=60.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if cond():
            return True
        time.sleep(0.02)
    raise AssertionError("timed out waiting")


def finished_units(out: Path) -> list[Path]:
    return sorted(p for p in (out / "units").glob("*.json") if not p.name.startswith("."))


# --------------------------------------------------------------------------- one run per folder
def test_a_second_run_while_one_runs_exits_2_naming_the_lock(tmp_path):
    exp = write_exp(tmp_path / "exp.yaml", EXP)
    ref = tmp_path / "ref"
    run_fake(exp, ref)
    out = tmp_path / "out"
    # the first run is held inside its first unit (it holds the lock) until the second ends:
    # the two overlap whatever the machine's load
    gate, calls = tmp_path / "gate", tmp_path / "calls"
    env = {"SIMLUNAR_TEST_GATE": str(gate), "SIMLUNAR_TEST_CALLS": str(calls)}
    winner = cli("run", str(exp), "--out", str(out), "--no-progress", env=env)
    try:
        wait_for(lambda: calls.is_dir() and any(calls.iterdir()), timeout=120)
        second = cli("run", str(exp), "--out", str(out), "--no-progress")
        out_err = second.communicate(timeout=120)  # reads the pipes while waiting
        loser = (second.returncode, *out_err)
    finally:
        gate.touch()
    out_err = winner.communicate(timeout=120)
    won = (winner.returncode, *out_err)
    assert (won[0], loser[0]) == (0, 2), (won, loser)
    lines = loser[2].splitlines()
    assert len(lines) == 1, loser[2]
    assert f"another simlunar run (pid {winner.pid}) is writing into this folder" in lines[0]
    assert str(out / ".lock") in lines[0]
    assert loser[1] == ""
    # the folder is that of one uninterrupted run (the lock file is gone)
    assert tree(out) == tree(ref)
    prov, prov_ref = (json.loads((d / "provenance.json").read_text()) for d in (out, ref))
    assert prov["files"] == prov_ref["files"] and prov["unit_keys"] == prov_ref["unit_keys"]


def test_a_held_lock_refuses_with_the_owner_pid_and_a_dead_owner_lock_is_taken_over(tmp_path):
    exp = write_exp(tmp_path / "exp.yaml", {**EXP, "sweep": {}})
    out = tmp_path / "out"
    out.mkdir()
    with FolderLock(out):
        r = CliRunner().invoke(app, ["run", str(exp), "--out", str(out), "--no-progress"])
        assert r.exit_code == 2
        assert f"(pid {os.getpid()})" in r.stderr and len(r.stderr.splitlines()) == 1
        assert sorted(p.name for p in out.iterdir()) == [".lock"]
    assert not (out / ".lock").exists()
    # a lock file left by a process that no longer exists is no lock
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)  # fmt: skip
    (out / ".lock").write_text(dead.stdout)
    s = run_fake(exp, out)
    assert s.units_computed == 1 and not (out / ".lock").exists()


# --------------------------------------------------------------------------- one config per folder
def test_another_config_into_a_finished_folder_is_refused_and_changes_nothing(tmp_path):
    exp = write_exp(tmp_path / "exp.yaml", EXP)
    out = tmp_path / "out"
    run_fake(exp, out)
    before = tree(out, skip=())
    other = write_exp(tmp_path / "other.yaml", {**EXP, "seed": 4})
    r = CliRunner().invoke(app, ["run", str(other), "--out", str(out), "--no-progress"])
    assert r.exit_code == 2, r.output
    assert r.stderr.splitlines() == [
        f"error: {out} holds the results of another configuration (seed: 3 in the folder, "
        "4 now); choose another --out or delete the folder"
    ]
    assert tree(out, skip=()) == before
    # the same config resumes (here: everything cached)
    assert run_fake(exp, out).units_cached == 4


def test_a_changed_dem_is_recomputed_and_its_results_differ(tmp_path):
    rng = np.random.default_rng(1)
    np.save(tmp_path / "dem.npy", rng.normal(0, 0.3, (24, 32)))
    data = {**EXP, "terrain": {"file": "dem.npy", "spacing_m": 0.2}, "sweep": {}}
    exp = write_exp(tmp_path / "exp.yaml", data)
    out = tmp_path / "out"

    def dem_unit(payload):
        # the fake unit's numbers depend on the DEM's contents, as a real unit's do
        rec = fake_unit(payload)
        h = np.load(payload["config"]["terrain"]["file"])
        for row in rec["rows"]:
            row["value"] *= float(np.abs(h).mean())
        return rec

    def go():
        cfg = load_experiment(exp)
        return run_experiment(cfg, out, compute=dem_unit, progress=False, figures=False)

    s1 = go()
    first = (out / "results.csv").read_bytes()
    prov1 = json.loads((out / "provenance.json").read_text())
    assert go().units_cached == 1  # unchanged input: cached
    np.save(tmp_path / "dem.npy", 5 * np.load(tmp_path / "dem.npy"))
    s2 = go()
    assert (s1.units_computed, s2.units_computed, s2.units_cached) == (1, 1, 0)
    assert (out / "results.csv").read_bytes() != first
    prov2 = json.loads((out / "provenance.json").read_text())
    (inp1,), (inp2,) = prov1["inputs"], prov2["inputs"]
    assert inp1["key"] == inp2["key"] == "terrain.file"
    assert inp2["sha256"] == hashlib.sha256((tmp_path / "dem.npy").read_bytes()).hexdigest()
    assert inp1["sha256"] != inp2["sha256"]
    # the old unit is gone: the folder holds only units of its current inputs
    assert [p.stem for p in finished_units(out)] == prov2["unit_keys"] != prov1["unit_keys"]


def test_kill_after_config_write_then_figures_and_another_config_refuse(tmp_path):
    exp = write_exp(tmp_path / "exp.yaml", EXP)
    ref = tmp_path / "ref"
    run_fake(exp, ref)
    out = tmp_path / "out"
    # every unit waits at a gate that never opens: killed inside the first one
    calls = tmp_path / "calls"
    env = {"SIMLUNAR_TEST_CALLS": str(calls), "SIMLUNAR_TEST_GATE": str(tmp_path / "never")}
    p = cli("run", str(exp), "--out", str(out), "--no-progress", env=env)
    wait_for(lambda: (out / "config.yaml").is_file() and calls.is_dir() and any(calls.iterdir()))
    os.killpg(p.pid, signal.SIGKILL)
    p.communicate()
    assert not (out / "results.csv").exists() and not (out / "provenance.json").exists()
    # (the killed run's .lock stays behind; a later run takes it over and removes it)
    before = tree(out, skip=(".lock",))
    runner = CliRunner()
    r = runner.invoke(app, ["figures", str(out)])
    assert r.exit_code == 2 and len(r.stderr.splitlines()) == 1
    assert "missing results.csv); an unfinished run: rerun it with the same config" in r.stderr
    other = write_exp(tmp_path / "other.yaml", {**EXP, "sweep": {"render.light.elevation_deg": [10, 90]}})  # fmt: skip
    r = runner.invoke(app, ["run", str(other), "--out", str(out), "--no-progress"])
    assert r.exit_code == 2 and "holds the results of another configuration (sweep." in r.stderr
    assert tree(out, skip=(".lock",)) == before
    # the same config finishes the run; the result equals an uninterrupted one
    run_fake(exp, out)
    assert tree(out) == tree(ref)


def test_a_folder_whose_files_disagree_is_refused_by_figures_and_repaired_by_a_rerun(tmp_path):
    """What an interrupted older simlunar could leave: a new config.yaml beside old results."""
    a = write_exp(tmp_path / "a.yaml", EXP)
    b = write_exp(tmp_path / "b.yaml", {**EXP, "seed": 9})
    out, ref_b = tmp_path / "out", tmp_path / "ref_b"
    run_fake(a, out)
    run_fake(b, ref_b)
    shutil.copy(ref_b / "config.yaml", out / "config.yaml")
    before = tree(out, skip=())
    r = CliRunner().invoke(app, ["figures", str(out)])
    assert r.exit_code == 2, r.output
    assert r.stderr.startswith(f"error: {out / 'config.yaml'}: does not belong to this folder")
    assert tree(out, skip=()) == before
    # a rerun of the folder's config recomputes everything and drops the other units
    s = run_fake(b, out)
    assert s.units_computed == 4
    assert tree(out) == tree(ref_b)


def test_figures_of_another_state_are_removed(tmp_path):
    exp = write_exp(tmp_path / "exp.yaml", {**EXP, "figures": {"enabled": True, "formats": ["png"], "sparse_mesh_density": None}})  # fmt: skip
    out = tmp_path / "out"
    cfg = load_experiment(exp)
    s = run_experiment(cfg, out, compute=fake_unit, progress=False)
    names = sorted(p.name for p in s.figures)
    assert "panels_unit3.png" in names
    (out / "figures" / "panels_unit7.png").write_bytes(b"old")
    (out / "figures" / "score_vs_spp_mse.pdf").write_bytes(b"old")
    r = CliRunner().invoke(app, ["figures", str(out)])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (out / "figures").iterdir()) == names


# --------------------------------------------------------------------------- figures on damage
@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("finished")
    exp = write_exp(d / "exp.yaml", {**EXP, "figures": {"enabled": True, "formats": ["png"], "sparse_mesh_density": None}})  # fmt: skip
    run_experiment(load_experiment(exp), d / "out", compute=fake_unit, progress=False)
    return d / "out"


def _first_npz(out: Path) -> Path:
    key = json.loads((out / "provenance.json").read_text())["unit_keys"][0]
    return out / "units" / f"{key}.npz"


DAMAGE = [
    (
        "garbage config.yaml",
        lambda o: (o / "config.yaml").write_text("{{{: [\n"),
        "config.yaml: not valid YAML",
    ),
    (
        "config.yaml a list",
        lambda o: (o / "config.yaml").write_text("- 1\n"),
        "config.yaml: not an experiment",
    ),
    (
        "garbage provenance.json",
        lambda o: (o / "provenance.json").write_text("{oops"),
        "provenance.json: not valid JSON",
    ),
    (
        "provenance.json without units",
        lambda o: (o / "provenance.json").write_text("{}"),
        "provenance.json: no 'unit_keys'",
    ),
    (
        "garbage results.csv",
        lambda o: (o / "results.csv").write_text("a,b\n1,2\n"),
        "results.csv: does not belong",
    ),
    (
        "empty results.csv",
        lambda o: (o / "results.csv").write_text(""),
        "results.csv: does not belong",
    ),
    (
        "missing unit",
        lambda o: _first_npz(o).with_suffix(".json").unlink(),
        ".json: unit missing or unreadable",
    ),
    (
        "corrupt unit arrays",
        lambda o: _first_npz(o).write_bytes(b"PK\x03\x04garbage"),
        ".npz: unreadable unit arrays",
    ),
    ("folder is a file", None, "is a file, not a folder"),
]


@pytest.mark.parametrize(("case", "damage", "expect"), DAMAGE, ids=[d[0] for d in DAMAGE])
def test_figures_on_a_damaged_folder_is_one_line_exit_2(case, damage, expect, finished, tmp_path):
    out = tmp_path / "out"
    if damage is None:
        out.write_text("x")
    else:
        shutil.copytree(finished, out)
        shutil.rmtree(out / "figures")
        damage(out)
    before = tree(tmp_path, skip=())
    r = CliRunner().invoke(app, ["figures", str(out)])
    assert r.exit_code == 2, r.output
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and expect in lines[0], r.stderr
    assert "Traceback" not in r.output
    assert tree(tmp_path, skip=()) == before


def test_figures_waits_for_no_run_it_refuses_while_one_writes(finished, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(finished, out)
    before = tree(out, skip=())
    with FolderLock(out):
        r = CliRunner().invoke(app, ["figures", str(out)])
        assert r.exit_code == 2 and f"(pid {os.getpid()}) is writing into this folder" in r.stderr
    assert tree(out, skip=()) == before


def test_figures_checks_rows_when_the_provenance_has_no_file_hashes(finished, tmp_path):
    """Folders of older versions carry no hashes: the table itself is still checked."""
    out = tmp_path / "out"
    shutil.copytree(finished, out)
    prov = json.loads((out / "provenance.json").read_text())
    del prov["files"]
    (out / "provenance.json").write_text(json.dumps(prov))
    (out / "results.csv").write_text("unit,metric,value\n0,mse,abc\n")
    r = CliRunner().invoke(app, ["figures", str(out)])
    assert r.exit_code == 2
    assert "results.csv: line 2: unit '0', value 'abc' are not numbers" in r.stderr
    (out / "results.csv").write_text("unit,metric,value\n")
    r = CliRunner().invoke(app, ["figures", str(out)])
    assert r.exit_code == 2 and "results.csv: no result rows" in r.stderr


# --------------------------------------------------------------------------- interrupts, bugs
def test_sigint_keeps_finished_units_says_so_in_one_line_and_resumes(tmp_path):
    exp = write_exp(tmp_path / "exp.yaml", EXP)
    ref = tmp_path / "ref"
    run_fake(exp, ref)
    out = tmp_path / "out"
    # two units finish, the third waits at a gate that never opens: interrupted there
    calls = tmp_path / "calls"
    env = {
        "SIMLUNAR_TEST_CALLS": str(calls),
        "SIMLUNAR_TEST_GATE": str(tmp_path / "never"),
        "SIMLUNAR_TEST_GATE_AFTER": "2",
    }
    p = cli("run", str(exp), "--out", str(out), "--no-progress", env=env)
    wait_for(
        lambda: (
            (out / "units").is_dir()
            and len(finished_units(out)) >= 2
            and len(list(calls.glob("*.call"))) >= 3
        ),
        timeout=120,
    )
    os.killpg(p.pid, signal.SIGINT)
    _, stderr = p.communicate(timeout=60)  # reads the pipes while waiting
    code = p.returncode
    assert code == 130, stderr
    kept = finished_units(out)
    assert stderr.splitlines() == [
        f"interrupted: {len(kept)} of 4 units finished and kept in {out / 'units'}; "
        "rerun the same command to resume"
    ]
    assert len(kept) == 2
    assert not (out / ".lock").exists()
    s = run_fake(exp, out)
    assert (s.units_cached, s.units_computed) == (len(kept), 4 - len(kept))
    assert tree(out) == tree(ref)


def test_an_internal_error_keeps_its_traceback_exit_1(tmp_path, monkeypatch):
    from simlunar.pipeline import runner

    def buggy(payload):
        return {}["rows"]  # a KeyError: a bug, not the user's mistake

    monkeypatch.setitem(runner.run_experiment.__kwdefaults__, "compute", buggy)
    exp = write_exp(tmp_path / "exp.yaml", {**EXP, "sweep": {}})
    r = CliRunner().invoke(app, ["run", str(exp), "--out", str(tmp_path / "o"), "--no-progress"])
    assert r.exit_code == 1
    assert "Traceback (most recent call last)" in r.stderr and "KeyError: 'rows'" in r.stderr
    assert (
        r.stderr.rstrip()
        .splitlines()[-1]
        .startswith(
            "simlunar: internal error (KeyError); this is a bug in simlunar, please report it"
        )
    )


def test_a_write_refused_during_the_run_is_one_line_exit_3(tmp_path, monkeypatch):
    from simlunar.pipeline import runner

    real = runner.atomic_write_text

    def full(fd):  # as the OS reports a full disk: an errno, no file name
        raise OSError(errno.ENOSPC, "No space left on device")

    def refuse(path, text):
        if Path(path).name == "results.csv":
            with monkeypatch.context() as m:
                m.setattr(os, "fsync", full)
                return real(path, text)
        return real(path, text)

    monkeypatch.setitem(runner.run_experiment.__kwdefaults__, "compute", fake_unit)
    monkeypatch.setattr(runner, "atomic_write_text", refuse)
    exp = write_exp(tmp_path / "exp.yaml", {**EXP, "sweep": {}})
    out = tmp_path / "o"
    r = CliRunner().invoke(app, ["run", str(exp), "--out", str(out), "--no-progress"])
    assert r.exit_code == 3
    assert r.stderr.splitlines() == [f"error: {out / 'results.csv'}: No space left on device"]
    assert len(finished_units(out)) == 1  # the finished unit is kept
    assert not list(out.glob(".results.csv.*"))  # no temporary file left


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EIO])
def test_an_environment_errno_without_a_file_name_is_exit_3(tmp_path, monkeypatch, code):
    from simlunar.pipeline import runner

    def unit(payload):
        raise OSError(code, os.strerror(code))  # e.g. from a writer that names no file

    monkeypatch.setitem(runner.run_experiment.__kwdefaults__, "compute", unit)
    exp = write_exp(tmp_path / "exp.yaml", {**EXP, "sweep": {}})
    r = CliRunner().invoke(app, ["run", str(exp), "--out", str(tmp_path / "o"), "--no-progress"])
    assert r.exit_code == 3, r.output
    assert r.stderr.splitlines() == [f"error: {os.strerror(code)}"]


def test_claim_folder_refuses_an_unrelated_folder(tmp_path):
    from simlunar.results.folder import claim_folder

    (tmp_path / "thesis.tex").write_text("x")
    with pytest.raises(ResultFolderError, match=r"not a simlunar result folder .* thesis\.tex"):
        claim_folder(tmp_path, "name: x\nstudy: {}\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["thesis.tex"]


def test_a_folder_written_before_a_new_option_takes_the_same_experiment(tmp_path):
    # first_round was added to the sequential options after result folders existed: a rerun
    # into such a folder was refused as "another configuration" though no number changes
    import yaml

    from simlunar.results.folder import claim_folder

    seq = {"strategy": "sequential", "sequential": {"prior": "wavelet", "max_rounds": 12}}
    old = {"name": "x", "study": {"strategies": ["random", "s"], "strategy_options": {"s": seq}}}
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(old))
    new = json.loads(json.dumps(old))
    new["study"]["strategy_options"]["s"]["sequential"]["first_round"] = "uniform"
    claim_folder(tmp_path, yaml.safe_dump(new))  # the same experiment
    assert yaml.safe_load((tmp_path / "config.yaml").read_text()) == new
    new["study"]["strategy_options"]["s"]["sequential"]["first_round"] = "prior"
    with pytest.raises(
        ResultFolderError, match=r"first_round: \"uniform\" in the folder, \"prior\" now"
    ):
        claim_folder(tmp_path, yaml.safe_dump(new))


def test_a_lost_cluster_is_one_line_exit_3_and_keeps_finished_units(tmp_path, monkeypatch):
    from simlunar.errors import InfrastructureError
    from simlunar.pipeline import runner

    def lost_on_third(payload):
        if payload["config"]["render"]["light"]["elevation_deg"] == 50:
            raise InfrastructureError("--scheduler tcp://10.0.0.1:8786: lost the connection")
        return fake_unit(payload)

    monkeypatch.setitem(runner.run_experiment.__kwdefaults__, "compute", lost_on_third)
    exp = write_exp(tmp_path / "exp.yaml", EXP)
    out = tmp_path / "o"
    r = CliRunner().invoke(app, ["run", str(exp), "--out", str(out), "--no-progress"])
    assert r.exit_code == 3, r.output
    assert r.stderr.splitlines() == [
        "error: --scheduler tcp://10.0.0.1:8786: lost the connection; 2 of 4 units finished "
        f"and kept in {out / 'units'}; rerun the same command to resume"
    ]
    assert len(finished_units(out)) == 2


@pytest.mark.slow
def test_real_units_a_dem_multiplied_by_5_is_recomputed(tmp_path):
    """A changed DEM file with real units: the same config, the DEM's heights times 5."""
    rng = np.random.default_rng(4)
    np.save(tmp_path / "dem.npy", rng.normal(0, 0.3, (24, 32)).cumsum(axis=1) * 0.2)
    data = {
        "name": "dem_change",
        "terrain": {"file": "dem.npy", "spacing_m": 0.2},
        "study": {"strategies": ["random", "grid"], "densities": [0.5, 0.25], "trials": 1},
        "figures": {"enabled": False},
    }
    exp = write_exp(tmp_path / "exp.yaml", data)
    out = tmp_path / "out"
    args = ["run", str(exp), "--out", str(out), "--no-progress"]
    r1 = CliRunner().invoke(app, args)
    assert r1.exit_code == 0, r1.output
    first = (out / "results.csv").read_bytes()
    np.save(tmp_path / "dem.npy", 5 * np.load(tmp_path / "dem.npy"))
    r2 = CliRunner().invoke(app, args)
    assert r2.exit_code == 0, r2.output
    assert "units: 1 (0 cached, 1 computed)" in r2.stdout
    assert (out / "results.csv").read_bytes() != first
    assert len(finished_units(out)) == 1


def test_every_shipped_experiment_passes_the_checks(with_shipped_models):
    """No false alarm: the preflight accepts every experiment in experiments/ (in a working
    folder with the learned-model files two of them name, as `simlunar train` makes them)."""
    from simlunar.pipeline.preflight import check_units
    from simlunar.pipeline.runner import expand

    paths = sorted((HERE.parents[1] / "experiments").glob("*.yaml"))
    assert len(paths) >= 10
    for path in paths:
        units = expand(load_experiment(path))
        assert len(check_units(units).terrain) == len(units)


def test_ctrl_c_while_the_summary_is_written_says_what_is_kept(tmp_path, monkeypatch):
    from simlunar.errors import RunInterrupted
    from simlunar.pipeline import runner

    def interrupt(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(runner, "collect_rows", interrupt)
    exp = write_exp(tmp_path / "exp.yaml", EXP)
    out = tmp_path / "out"
    with pytest.raises(RunInterrupted, match=r"^interrupted: 4 of 4 units finished and kept in"):
        run_fake(exp, out)
    assert not (out / ".lock").exists() and not (out / "provenance.json").exists()
    monkeypatch.undo()
    assert run_fake(exp, out).units_cached == 4


# --------------------------------------------------------------------------- lost pool workers
def _children(pid: int) -> list[int]:
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


POOL_EXP = {
    **EXP,
    "study": {
        "strategies": ["random", "grid", "gradient"],
        "densities": ["1/4", "1/16", "1/64"],
        "trials": 12,
        "metrics": ["mse"],
    },
    "sweep": {"render.light.elevation_deg": [10, 30]},
}


def test_a_killed_study_worker_is_exit_3_in_seconds_keeps_units_and_a_rerun_completes(tmp_path):
    """``--workers 2``: a forked sampling-study process killed (the OOM killer, an operator)
    ends the run with one line and exit 3 instead of a hang; the finished unit is kept and
    the rerun gives the folder of an uninterrupted run."""
    from fake_unit import pool_unit

    exp = write_exp(tmp_path / "exp.yaml", POOL_EXP)
    ref = tmp_path / "ref"
    run_experiment(load_experiment(exp), ref, compute=pool_unit, progress=False, figures=False)
    out, gate, calls = tmp_path / "out", tmp_path / "gate", tmp_path / "calls"
    env = {
        "SIMLUNAR_TEST_POOL_UNITS": "1",
        "SIMLUNAR_TEST_CALLS": str(calls),
        "SIMLUNAR_TEST_GATE": str(gate),
        "SIMLUNAR_TEST_GATE_AFTER": "1",
    }
    p = cli("run", str(exp), "--out", str(out), "--no-progress", "--workers", "2", env=env)
    try:
        # the first unit finishes while the second waits at the gate; then the second's pool
        # starts and one of its workers is killed
        wait_for(lambda: (out / "units").is_dir() and len(finished_units(out)) == 1, 120)
        gate.touch()
        victims: list[int] = []
        wait_for(lambda: victims.extend(_children(p.pid)) or victims, 60)
        os.kill(victims[0], signal.SIGKILL)
        t0 = time.monotonic()
        _, stderr = p.communicate(timeout=60)
        took = time.monotonic() - t0
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
    assert p.returncode == 3, stderr
    assert took < 20, took
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: a study worker process died")
    assert "1 of 2 units finished and kept" in lines[0]
    assert len(finished_units(out)) == 1 and not (out / ".lock").exists()
    s = run_experiment(load_experiment(exp), out, compute=pool_unit, progress=False, figures=False)
    assert (s.units_cached, s.units_computed) == (1, 1)
    assert tree(out) == tree(ref)


# --------------------------------------------------------------------------- Ctrl-C at start-up
def _maps_have(pid: int, name: str) -> bool:
    try:
        return name in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return False


@pytest.mark.render
@pytest.mark.parametrize("after_s", [0.0, 0.05, 0.2, 0.4])
def test_ctrl_c_while_the_renderer_starts_is_always_130(after_s, tmp_path):
    """SIGINT at several points of Mitsuba's and Dr.Jit's import and initialisation (timed
    from the moment Dr.Jit's library is mapped): exit 130 and the one line, never an internal
    error, an abort or a finished render."""
    ROOT = HERE.parents[1]
    out = tmp_path / "r"
    p = subprocess.Popen(
        [sys.executable, "-m", "simlunar.cli", "render", str(ROOT / "scenes" / "quickstart_scene.yaml"), "--out", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
    )  # fmt: skip
    try:
        wait_for(lambda: _maps_have(p.pid, "drjit") or p.poll() is not None, timeout=120)
        time.sleep(after_s)
        os.killpg(p.pid, signal.SIGINT)
        _, stderr = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
    assert p.returncode == 130, stderr
    assert stderr.splitlines() == ["interrupted"], stderr
