"""The runner: sweep expansion, cache keys, resume, determinism and executors.

These tests use :mod:`fake_unit` (cheap and deterministic) because they are about the
runner's bookkeeping; ``test_end_to_end.py`` runs real units (terrain, Mitsuba, study).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from fake_unit import fake_unit

from simlunar.config.schema import ExperimentCfg
from simlunar.pipeline.executors import LocalPoolExecutor, make_executor
from simlunar.pipeline.rows import collect_rows
from simlunar.pipeline.runner import expand, run_experiment, unit_key

HERE = Path(__file__).resolve().parent


def cfg(**over) -> ExperimentCfg:
    d = {
        "name": "sweep_test",
        "seed": 7,
        "terrain": {"preset": "aerial_1", "scale": 0.125},
        "study": {
            "strategies": ["random", "grid", "wavelet"],
            "densities": {"from": "1/2", "to": "1/32", "count": 5},
            "trials": 3,
            "metrics": ["mse", "grad"],
        },
        "sweep": {"render.light.elevation_deg": [10, 30, 60, 90]},
    }
    d.update(over)
    return ExperimentCfg.model_validate(d)


def test_expand_is_the_cartesian_product_in_order():
    c = cfg(
        sweep={"render.light.elevation_deg": [10, 30], "render.bsdf.kind": ["lambert", "hapke"]}
    )
    units = expand(c)
    assert [u.sweep for u in units] == [
        {"render.light.elevation_deg": 10, "render.bsdf.kind": "lambert"},
        {"render.light.elevation_deg": 10, "render.bsdf.kind": "hapke"},
        {"render.light.elevation_deg": 30, "render.bsdf.kind": "lambert"},
        {"render.light.elevation_deg": 30, "render.bsdf.kind": "hapke"},
    ]
    assert units[1].config["render"]["bsdf"]["kind"] == "hapke"
    assert units[2].config["render"]["light"]["elevation_deg"] == 30
    assert len({u.key for u in units}) == 4
    assert "sweep" not in units[0].config


def test_kind_axes_apply_before_their_fields():
    units = expand(
        cfg(sweep={"render.light.elevation_deg": [10, 50], "render.light.kind": ["sun"]})
    )
    assert [u.config["render"]["light"]["elevation_deg"] for u in units] == [10, 50]


def test_cache_key_ignores_name_and_figure_formats_but_not_numbers():
    a = expand(cfg(sweep={}))[0]
    b = expand(cfg(sweep={}, name="renamed", description="x", figures={"formats": ["png"]}))[0]
    c = expand(cfg(sweep={}, seed=8))[0]
    d = expand(cfg(sweep={}, render={"spp": 17}))[0]
    assert a.key == b.key
    assert len({a.key, c.key, d.key}) == 3
    assert unit_key(a.config) == a.key


def test_the_default_reconstructions_keep_the_cache_key_of_before():
    a = expand(cfg(sweep={}))[0]
    assert a.config["study"]["reconstructions"] == ["linear"]
    before = {**a.config, "study": {k: v for k, v in a.config["study"].items()
                                    if k != "reconstructions"}}  # fmt: skip
    assert unit_key(before, a.inputs) == a.key
    # no extra guide frame (the render default) keeps the key of before too
    from simlunar.config.render import RenderCfg
    from simlunar.results.cache_keys import NEW_RENDER_DEFAULTS

    assert {k: RenderCfg().model_dump()[k] for k in NEW_RENDER_DEFAULTS} == NEW_RENDER_DEFAULTS
    assert a.config["render"]["guide_frames"] == []
    old = {**before, "render": {k: v for k, v in a.config["render"].items() if k != "guide_frames"}}
    assert unit_key(old, a.inputs) == a.key
    framed = expand(cfg(sweep={}, render={"guide_frames": ["camera"]}))[0]
    assert framed.key != a.key
    study = dict(cfg().study.model_dump(mode="json"))
    other = expand(
        cfg(sweep={}, study={**study, "reconstructions": [{"linear": {"outside": "nan"}}]})
    )
    assert other[0].key != a.key


def test_a_terrain_without_refine_or_rocks_and_a_fit_without_budgets_keep_their_keys():
    # terrain.refine_m / terrain.rocks and a LIDAR fit's budget_s / budget_j came after caches
    # existed: at their defaults (None) a unit keys as before and a folder is the same
    # experiment; set, the key changes
    from simlunar.config.lidar import FitCfg
    from simlunar.config.terrain import TerrainCfg
    from simlunar.results.cache_keys import NEW_NESTED_DEFAULTS, NEW_TERRAIN_DEFAULTS
    from simlunar.results.folder import _identity

    dumped = TerrainCfg(preset="aerial_1").model_dump()
    assert {k: dumped[k] for k in NEW_TERRAIN_DEFAULTS} == NEW_TERRAIN_DEFAULTS
    fit = FitCfg().model_dump()
    assert {k: fit[k] for k in NEW_NESTED_DEFAULTS["fit"]} == NEW_NESTED_DEFAULTS["fit"]
    a = expand(cfg(sweep={}))[0]
    assert a.config["terrain"]["rocks"] is None and a.config["terrain"]["refine_m"] is None
    old_terrain = {k: v for k, v in a.config["terrain"].items() if k not in NEW_TERRAIN_DEFAULTS}
    before = {**a.config, "terrain": old_terrain}
    assert unit_key(before, a.inputs) == a.key
    assert _identity(before) == _identity(a.config)
    study = {"kind": "lidar", "planners": ["grid", "timed"], "densities": ["1/64"],
             "planner_opts": {"timed": {"strategy": "random", "fit": {"kind": "scan_time"}}}}  # fmt: skip
    lidar = expand(cfg(sweep={}, study=study, render={"camera": {
        "kind": "perspective", "width": 64, "height": 48, "fov_deg": 40,
        "position_m": [20.0, -12.0, 30.0], "look_at_m": [20.0, -12.5, 0.0]}}))[0]  # fmt: skip
    opts = lidar.config["study"]["planner_opts"]["timed"]
    assert opts["fit"]["budget_s"] is None
    no_budgets = {k: v for k, v in opts["fit"].items() if k not in ("budget_s", "budget_j")}
    old_study = {**lidar.config["study"],
                 "planner_opts": {"timed": {**opts, "fit": no_budgets}}}  # fmt: skip
    assert unit_key({**lidar.config, "study": old_study}, lidar.inputs) == lidar.key


def test_hapke_units_keep_their_key_without_the_coherent_backscatter_keys():
    # the keys B_C0 and h_C came after Hapke caches existed: unset (the surge of before, none)
    # they leave the key as it was; set, the key changes
    from simlunar.config.render import HapkeCfg
    from simlunar.results.cache_keys import NEW_BSDF_DEFAULTS

    unset = HapkeCfg(kind="hapke").model_dump()
    assert {k: unset[k] for k in NEW_BSDF_DEFAULTS["hapke"]} == NEW_BSDF_DEFAULTS["hapke"]
    a = expand(cfg(sweep={}, render={"bsdf": {"kind": "hapke"}}))[0]
    bsdf = a.config["render"]["bsdf"]
    assert bsdf["B_C0"] is None and bsdf["h_C"] is None
    old_bsdf = {k: v for k, v in bsdf.items() if k not in ("B_C0", "h_C")}
    before = {**a.config, "render": {**a.config["render"], "bsdf": old_bsdf}}
    assert unit_key(before, a.inputs) == a.key
    surged = expand(cfg(sweep={}, render={"bsdf": {"kind": "hapke", "B_C0": 0.5}}))[0]
    assert surged.key != a.key


def test_a_reconstruction_with_a_results_version_has_it_in_the_key():
    from simlunar.reconstruction import RECONSTRUCTIONS
    from simlunar.results.cache_keys import reconstruction_versions

    assert RECONSTRUCTIONS["learned"].meta["results_version"] == 2
    recons = ["linear", "shading", {"learned": {"model": "m.joblib"}},
              {"l2": {"reconstruction": "learned", "model": "n.joblib"}}]  # fmt: skip
    assert reconstruction_versions({"reconstructions": recons}) == {"shading": 4, "learned": 2}
    # shading 2: its held-out check pools folds and remakes the detail from the kept samples;
    # 3: a flash's second pass (flash_refine) reads around the fused surface's slopes; 4: the
    # detail is limited to detail_clip x the held-out departures' RMS
    assert reconstruction_versions({"reconstructions": ["linear", "shading"]}) == {"shading": 4}
    assert reconstruction_versions({"reconstructions": ["linear", "smoothed"]}) == {}
    a = expand(cfg(sweep={}))[0]
    config = {**a.config, "study": {**a.config["study"], "reconstructions": recons}}
    before = unit_key(config, a.inputs)
    meta = RECONSTRUCTIONS["learned"].meta
    try:  # a new version of the method: a new key for the same config
        meta["results_version"] = 3
        assert unit_key(config, a.inputs) != before
    finally:
        meta["results_version"] = 2
    assert unit_key(config, a.inputs) == before


def test_cached_rows_without_a_reconstruction_are_linear_rows():
    u = expand(cfg(sweep={}))[0]
    rows = [{"strategy": "grid", "density": 0.5, "k": 2, "trial": 0, "metric": "mse", "value": 1.0}]
    out, columns = collect_rows([u], {u.key: {"rows": rows}})
    assert columns == ["unit", "strategy", "reconstruction", "density", "k", "trial", "metric",
                       "value"]  # fmt: skip
    assert out[0]["reconstruction"] == "linear"


def _run(c, out, **kw):
    return run_experiment(c, out, compute=fake_unit, progress=False, figures=False, **kw)


def test_same_seed_twice_is_byte_identical_and_rerun_is_cached(tmp_path, monkeypatch):
    calls = tmp_path / "calls"
    monkeypatch.setenv("SIMLUNAR_TEST_CALLS", str(calls))
    s1 = _run(cfg(), tmp_path / "a")
    s2 = _run(cfg(), tmp_path / "b")
    a = (tmp_path / "a" / "results.csv").read_bytes()
    assert a == (tmp_path / "b" / "results.csv").read_bytes()
    assert (s1.units_computed, s2.units_computed) == (4, 4)
    assert len(list(calls.iterdir())) == 8
    s3 = _run(cfg(), tmp_path / "a")
    assert (s3.units_cached, s3.units_computed) == (4, 0)
    assert len(list(calls.iterdir())) == 8
    assert (tmp_path / "a" / "results.csv").read_bytes() == a
    # 4 units x 3 strategies x 5 densities x 3 trials x 2 metrics, plus the header
    lines = a.decode().splitlines()
    assert len(lines) == 1 + 4 * 3 * 5 * 3 * 2
    assert lines[0] == (
        "unit,render.light.elevation_deg,strategy,reconstruction,density,k,trial,metric,value"
    )
    prov = json.loads((tmp_path / "a" / "provenance.json").read_text())
    assert prov["units"] == {"total": 4, "cached": 4, "computed": 0}
    assert prov["seed"] == 7 and "numpy" in prov["versions"]
    # a different seed changes the numbers
    _run(cfg(seed=8), tmp_path / "c")
    assert (tmp_path / "c" / "results.csv").read_bytes() != a


def test_results_order_does_not_depend_on_completion_order(tmp_path):
    serial = _run(cfg(), tmp_path / "serial")
    units = expand(cfg())

    class Reversed:
        name = "reversed"

        def run(self, fn, payloads):
            for i in reversed(range(len(payloads))):
                yield i, fn(payloads[i])

        def describe(self):
            return {"executor": self.name}

    _run(cfg(), tmp_path / "rev", executor=Reversed())
    assert serial.units_total == len(units)
    assert (tmp_path / "serial" / "results.csv").read_bytes() == (
        tmp_path / "rev" / "results.csv"
    ).read_bytes()


def test_local_pool_gives_the_serial_results(tmp_path):
    _run(cfg(), tmp_path / "serial")
    _run(cfg(), tmp_path / "pool", executor=LocalPoolExecutor(2))
    assert (tmp_path / "serial" / "results.csv").read_bytes() == (
        tmp_path / "pool" / "results.csv"
    ).read_bytes()


def _finished(units_dir: Path) -> list[Path]:
    """Finished unit records (a hidden ``.<name>.tmp.json`` is a write cut short)."""
    return [p for p in units_dir.glob("*.json") if not p.name.startswith(".")]


@pytest.mark.slow
def test_sigkill_then_resume_recomputes_nothing_finished(tmp_path, monkeypatch):
    """Kill the run part-way (SIGKILL, no cleanup), resume, compare with an uninterrupted run."""
    c = cfg(sweep={"render.light.elevation_deg": [5, 15, 30, 45, 60, 90]})
    _run(c, tmp_path / "ref")
    out, calls = tmp_path / "killed", tmp_path / "calls"
    script = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(HERE)!r})
        from fake_unit import fake_unit
        from simlunar.config.loading import ExperimentCfg
        from simlunar.pipeline.runner import run_experiment
        cfg = ExperimentCfg.model_validate_json({c.model_dump_json(by_alias=True)!r})
        run_experiment(cfg, {str(out)!r}, compute=fake_unit, progress=False, figures=False)
    """)
    # two units finish, the third waits at a gate that never opens: killed there, whatever the
    # machine's load
    env = {
        **os.environ,
        "SIMLUNAR_TEST_CALLS": str(calls),
        "SIMLUNAR_TEST_GATE": str(tmp_path / "never"),
        "SIMLUNAR_TEST_GATE_AFTER": "2",
    }
    proc = subprocess.Popen([sys.executable, "-c", script], env=env, start_new_session=True)
    units_dir = out / "units"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        n_calls = len(list(calls.glob("*.call"))) if calls.is_dir() else 0
        if units_dir.is_dir() and len(_finished(units_dir)) >= 2 and n_calls >= 3:
            break
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = sorted(p.name for p in _finished(units_dir))
    assert len(done) == 2, done
    mtimes = {p.name: p.stat().st_mtime_ns for p in _finished(units_dir)}
    assert not (out / "results.csv").exists()
    n_calls_before = len(list(calls.iterdir()))

    monkeypatch.setenv("SIMLUNAR_TEST_CALLS", str(calls))
    s = _run(c, out)
    assert s.units_cached == len(done)
    assert s.units_computed == 6 - len(done)
    # finished units were neither recomputed nor rewritten
    assert len(list(calls.iterdir())) == n_calls_before + 6 - len(done)
    for name, t in mtimes.items():
        assert (units_dir / name).stat().st_mtime_ns == t
    # a write cut short leaves at most a hidden temporary file, never a partial unit
    assert all(p.suffix in (".json", ".npz") or p.name.startswith(".") for p in units_dir.iterdir())
    assert (out / "results.csv").read_bytes() == (tmp_path / "ref" / "results.csv").read_bytes()


@pytest.mark.slow
def test_dask_local_cluster_through_the_scheduler_path_matches_the_pool(tmp_path):
    import distributed

    _run(cfg(), tmp_path / "local", executor=LocalPoolExecutor(1))
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        ex = make_executor(scheduler=cluster.scheduler_address)
        s = _run(cfg(), tmp_path / "dask", executor=ex)
    assert s.units_computed == 4
    assert (tmp_path / "local" / "results.csv").read_bytes() == (
        tmp_path / "dask" / "results.csv"
    ).read_bytes()
    prov = json.loads((tmp_path / "dask" / "provenance.json").read_text())
    assert prov["executor"]["executor"] == "dask"


def test_executor_options():
    assert make_executor().describe() == {"executor": "local", "workers": 1}
    assert make_executor(workers=3).describe() == {"executor": "local", "workers": 3}
    with pytest.raises(ValueError, match="either --workers or --scheduler"):
        make_executor(workers=2, scheduler="tcp://localhost:1")
    with pytest.raises(ValueError, match="--workers must be >= 1"):
        make_executor(workers=0)


def test_progress_bar_gets_within_unit_progress_in_process(tmp_path, capsys):
    import fake_unit as fu

    fu.PROGRESS_CALLS.clear()
    s = run_experiment(
        cfg(), tmp_path / "p", compute=fu.fake_unit_with_progress, progress=True, figures=False
    )
    assert s.units_computed == 4
    assert fu.PROGRESS_CALLS == [(e, d) for e in (10, 30, 60, 90) for d in (1, 2, 3)]
    # stderr is not a terminal here: progress as lines, one per unit
    assert "sweep_test: 4/4 units, " in capsys.readouterr().err
    # without a bar, the unit function is called without a callback
    fu.PROGRESS_CALLS.clear()
    run_experiment(
        cfg(), tmp_path / "q", compute=fu.fake_unit_with_progress, progress=False, figures=False
    )
    assert fu.PROGRESS_CALLS == []


def test_without_random_the_tables_say_why_and_the_vs_grid_table_stays(tmp_path):
    # docs/experiments.md's first --set example (study.strategies=[grid, wavelet]) wrote a
    # score table of dashes, an empty scores.csv and no samples-saved table
    study = {**cfg().study.model_dump(), "strategies": ["grid", "wavelet"]}
    study["densities"] = [0.5, 0.25, 0.125, 0.0625, 0.03125]
    s = _run(cfg(sweep={}, study=study), tmp_path / "o")
    md = (tmp_path / "o" / "scores.md").read_text()
    assert s.scores_markdown == md
    assert "the random strategy, which study.strategies (grid, wavelet) does not include" in md
    assert "| –" not in md and "x  trials" not in md
    assert "### sweep_test: samples saved vs Grid at equal MSE" in md
    assert "| Wavelet |" in md
    # never a scores.csv of a header only (this fake unit has per-unit scores, a real one
    # without random has none: then scores.md says "no scores.csv")
    csv_lines = (tmp_path / "o" / "scores.csv").read_text().splitlines()
    assert len(csv_lines) > 1 and "no scores.csv" not in md


def test_a_rerun_keeps_the_run_time_and_adds_its_own(tmp_path):
    _run(cfg(sweep={}), tmp_path / "o")
    first = json.loads((tmp_path / "o" / "provenance.json").read_text())["timings"]
    _run(cfg(sweep={}), tmp_path / "o")
    again = json.loads((tmp_path / "o" / "provenance.json").read_text())["timings"]
    assert again["run_s"] == first["run_s"] and "rerun_s" in again
    # a new description (outside the cache key, as the docs say) is the same folder
    s = _run(cfg(sweep={}, description="edited"), tmp_path / "o")
    assert s.units_computed == 0


def test_a_rerun_redraws_no_figure_unless_its_inputs_changed(tmp_path):
    from simlunar.results.figures import write_figures

    c = cfg(sweep={}, figures={"sparse_mesh_density": None, "formats": ["png"]})
    out = tmp_path / "o"
    s1 = run_experiment(c, out, compute=fake_unit, progress=False)
    pngs = sorted(p for p in s1.figures if p.suffix == ".png")
    assert pngs and not any(p.suffix == ".pdf" for p in s1.figures)  # PNG only by default
    stamp = {p: p.stat().st_mtime_ns for p in pngs}
    s2 = run_experiment(c, out, compute=fake_unit, progress=False)
    assert sorted(s2.figures) == sorted(s1.figures)
    assert {p: p.stat().st_mtime_ns for p in pngs} == stamp  # nothing redrawn
    # a figure deleted is drawn again; PDF on request; --force redraws
    pngs[0].unlink()
    write_figures(out)
    assert pngs[0].is_file()
    both = write_figures(out, formats=("png", "pdf"))
    assert any(p.suffix == ".pdf" for p in both)
    before = pngs[-1].stat().st_mtime_ns
    write_figures(out, formats=("png", "pdf"), force=True)
    assert pngs[-1].stat().st_mtime_ns != before


def test_the_tables_code_is_the_code_this_process_loaded(monkeypatch):
    # hashed when the run starts, not when it writes its tables: a table module edited during
    # a long run labelled the old code's tables with the new code's hash, so a rerun kept them
    from simlunar.results import summaries

    before = summaries.tables_code()
    monkeypatch.setattr(summaries, "file_sha256", lambda path: "edited since")
    assert summaries.tables_code() == before


def test_every_swept_key_is_a_results_column_named_by_its_path(tmp_path):
    # a scalar axis, a dict axis and a list-of-dicts axis: each a column of results.csv named
    # by its YAML path, its cells the swept value as JSON (pandas groups by them as they are)
    import csv
    import json

    frames = [["ideal"], [{"flash": {"baseline_m": 5, "sun_ratio": 0.01, "daylight": True}}]]
    sweep = {
        "render.light": [{"kind": "sun", "elevation_deg": 30, "azimuth_deg": 135}],
        "render.guide_frames": frames,
        "render.spp": [4, 8],
    }
    c = cfg(sweep=sweep)
    _run(c, tmp_path / "o")
    with open(tmp_path / "o" / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0])[:4] == ["unit", "render.light", "render.guide_frames", "render.spp"]
    seen = {(r["render.guide_frames"], r["render.spp"]) for r in rows}
    assert len(seen) == 4
    for r in rows:
        assert json.loads(r["render.guide_frames"]) in frames
        assert json.loads(r["render.light"]) == sweep["render.light"][0]
    # the setting as written ("ideal") in the column, the configuration it means in the key
    units = expand(c)
    ideal = units[0]
    camera = expand(cfg(sweep={**sweep, "render.guide_frames": [["camera"]]}))[0]
    assert ideal.sweep["render.guide_frames"] == ["ideal"] and ideal.key == camera.key
