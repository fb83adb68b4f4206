"""A rerun of a finished quickstart: nothing computed, no figure redrawn (goal: < 3 s).

``simlunar run experiments/quickstart.yaml`` into a fresh folder, then the same command three
times as a user types it (a new interpreter each time, imports included); ``ours_s`` is the
median wall time of the reruns, ``rerun_cpu_s`` their median CPU time (user + system, what the
wall time is on an idle machine). There is no reference path (``reference_s`` None); the load
average is recorded beside the times, since a shared machine stretches wall times.
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
QUICKSTART = ROOT / "experiments" / "quickstart.yaml"
GOAL_S = 3.0
#: ``smoke=True``: the quickstart shrunk (same commands): a 1/32-scale scene, two strategies,
#: three densities, one trial, and one rerun instead of three
SMOKE_SET = (
    "terrain.scale=0.03",
    "render.spp=1",
    "study.strategies=[random, grid]",
    "study.strategy_options={}",
    "study.densities={from: 1/2, to: 1/8, count: 3}",
    "study.trials=1",
)


def _children_cpu_s() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def _cli(out: Path, sets=()) -> tuple[float, float, str]:
    cmd = [sys.executable, "-m", "simlunar.cli", "run", str(QUICKSTART), "--out", str(out)]
    for s in sets:
        cmd += ["--set", s]
    c0, t0 = _children_cpu_s(), time.perf_counter()
    r = subprocess.run(
        [*cmd, "--no-progress"], cwd=ROOT, capture_output=True, text=True, check=False
    )
    wall, cpu = time.perf_counter() - t0, _children_cpu_s() - c0
    if r.returncode != 0:
        raise RuntimeError(f"simlunar run failed ({r.returncode}): {r.stderr.strip()[-300:]}")
    return wall, cpu, r.stdout


def rerun(*, smoke: bool = False) -> dict:
    """First run and reruns of the quickstart (``smoke``: a shrunk quickstart, one rerun)."""
    sets = SMOKE_SET if smoke else ()
    with tempfile.TemporaryDirectory(prefix="simlunar-rerun-") as tmp:
        out = Path(tmp) / "quickstart"
        first_s, _, _ = _cli(out, sets)
        figures = sorted((out / "figures").iterdir())
        drawn = {p.name: p.stat().st_mtime_ns for p in figures}
        times, cpus = [], []
        for _ in range(1 if smoke else 3):
            wall, cpu, stdout = _cli(out, sets)
            if "(1 cached, 0 computed)" not in stdout:
                raise RuntimeError("the rerun computed a unit")
            times.append(wall)
            cpus.append(cpu)
        redrawn = sum(p.stat().st_mtime_ns != drawn[p.name] for p in figures)
    ours = statistics.median(times)
    return {
        "reference_s": None,
        "ours_s": round(ours, 3),
        "smoke": smoke,
        "first_run_s": round(first_s, 3),
        "reruns_s": [round(t, 3) for t in times],
        # CPU seconds of a rerun: its wall time on an idle machine, whatever the load now
        "rerun_cpu_s": round(statistics.median(cpus), 3),
        "figures_redrawn": redrawn,
        "goal_s": GOAL_S,
        "meets_goal_at_this_load": ours < GOAL_S,
        "meets_goal_idle": statistics.median(cpus) < GOAL_S,
        "load_1min": round(os.getloadavg()[0], 2),
    }


BENCHMARKS = {"rerun": rerun}
