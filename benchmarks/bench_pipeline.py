"""Pipeline benchmarks: ``sweep_workers`` (the same sweep with 2 local workers vs 1).

The sweep is ``experiments/ablation_sun_elevation.yaml`` (quarter-scale aerial scene 1,
250 x 400 cells) over four sun elevations: four real work units (terrain, Mitsuba render,
sensor, sampling study of 5 strategies x 10 densities x 5 trials, Fig. 4 sparse mesh). Each run writes to a fresh folder, so nothing is cached; a one-unit warm-up run
first fills Dr.Jit's kernel cache so neither timed run pays for compilation alone.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from simlunar.pipeline.config import load_experiment
from simlunar.pipeline.executors import LocalPoolExecutor
from simlunar.pipeline.runner import run_experiment

ROOT = Path(__file__).resolve().parents[1]
EXPERIMENT = ROOT / "experiments" / "ablation_sun_elevation.yaml"
SWEEP = {"sweep": {"render.light.elevation_deg": [10, 30, 50, 70]}}
WARMUP = {"sweep": {"render.light.elevation_deg": [20]}, "terrain.scale": 0.0625}


def _run(workers: int, overrides: dict, out: Path) -> float:
    cfg = load_experiment(EXPERIMENT, overrides)
    t = time.perf_counter()
    s = run_experiment(cfg, out, executor=LocalPoolExecutor(workers), progress=False, figures=False)
    elapsed = time.perf_counter() - t
    assert s.units_computed == s.units_total, "a benchmark run must compute every unit"
    return elapsed


def sweep_workers() -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        _run(1, WARMUP, tmp / "warmup")
        one = _run(1, SWEEP, tmp / "one")
        two = _run(2, SWEEP, tmp / "two")
        same = (tmp / "one" / "results.csv").read_bytes() == (
            tmp / "two" / "results.csv"
        ).read_bytes()
    return {"reference_s": one, "ours_s": two, "units": 4, "workers": 2, "identical_results": same}


BENCHMARKS = {"sweep_workers": sweep_workers}
