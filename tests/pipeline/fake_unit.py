"""A cheap, deterministic stand-in for a work unit (runner tests that are not about rendering).

It depends on the unit's config and seed exactly as a real unit does (rows per strategy,
density, trial and metric; the light elevation shifts the numbers), and counts its calls in a
folder given by ``SIMLUNAR_TEST_CALLS`` so tests can prove which units were recomputed.
``SIMLUNAR_TEST_GATE`` holds units until a file exists (:func:`enter_unit`).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from simlunar.config.schema import ExperimentCfg
from simlunar.pipeline.unit import stage_seeds


def enter_unit(payload: dict) -> None:
    """Count the call (``SIMLUNAR_TEST_CALLS``) and wait at the gate.

    ``SIMLUNAR_TEST_GATE`` (a path): a call waits until that file exists, except the first
    ``SIMLUNAR_TEST_GATE_AFTER`` calls (default 0; counted in ``SIMLUNAR_TEST_CALLS``). A test
    can so stop a run after exactly N units, whatever the machine's load, then kill it.
    """
    calls = os.environ.get("SIMLUNAR_TEST_CALLS")
    n_calls = 0
    if calls:
        Path(calls).mkdir(parents=True, exist_ok=True)
        # this call's number, taken atomically (O_EXCL): counting the files after writing one
        # let two concurrent units both see 2 calls, and both wait at the gate for ever
        while True:
            n_calls += 1
            try:
                fd = os.open(Path(calls) / f"{n_calls}.call", os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            except FileExistsError:
                continue
            with os.fdopen(fd, "w") as f:
                f.write(payload["config"]["name"])
            break
    gate = os.environ.get("SIMLUNAR_TEST_GATE")
    after = int(os.environ.get("SIMLUNAR_TEST_GATE_AFTER", "0"))
    if gate and (not calls or n_calls > after):
        deadline = time.monotonic() + 120
        while not Path(gate).exists():
            if time.monotonic() > deadline:
                raise RuntimeError(f"SIMLUNAR_TEST_GATE {gate} never appeared")
            time.sleep(0.02)


def gated(compute):
    """``compute`` (e.g. the real ``stages.compute_unit``) behind :func:`enter_unit`."""

    def unit(payload: dict) -> dict:
        enter_unit(payload)
        return compute(payload)

    return unit


def fake_unit(payload: dict) -> dict:
    cfg = ExperimentCfg.model_validate(payload["config"])
    enter_unit(payload)
    delay = float(os.environ.get("SIMLUNAR_TEST_DELAY", "0"))
    if delay:
        time.sleep(delay)
    s = cfg.study
    rng = np.random.default_rng(stage_seeds(cfg.seed)["study"])
    shift = getattr(cfg.render.light, "elevation_deg", 45.0) / 90.0
    rows = []
    for strategy in s.strategies:
        for d in s.densities:
            for t in range(s.trials):
                for m in s.metrics:
                    rows.append(
                        {
                            "strategy": strategy,
                            "density": d,
                            "k": max(3, round(d * 1024)),
                            "trial": t,
                            "metric": m,
                            "value": float((1 + shift) * (1 / d) ** 0.5 * rng.gamma(4.0)),
                        }
                    )
    scores = {
        m: {st: 1.0 + 0.1 * i + shift for i, st in enumerate(s.strategies)} for m in s.metrics
    }
    img = rng.random((16, 16)).astype(np.float32)
    return {
        "rows": rows,
        "scores": scores,
        "timings": {"study_s": 0.0},
        "arrays": {
            "image": img,
            "depth": img.astype(np.float64) * 2,
            "wavelet_energy": img**2,
            "plan_rows": np.arange(8, dtype=np.int32),
            "plan_cols": np.arange(8, dtype=np.int32),
            "reconstruction": img.astype(np.float64) * 2.1,
        },
        "meta": {"variant": "fake"},
    }


PROGRESS_CALLS: list[tuple] = []


def fake_unit_with_progress(payload: dict, *, progress=None) -> dict:
    """``fake_unit`` that reports within-unit progress, as ``stages.compute_unit`` does."""
    if progress is not None:
        for done in range(3):
            progress("study", done + 1, 3)
            PROGRESS_CALLS.append((payload["config"]["render"]["light"]["elevation_deg"], done + 1))
    return fake_unit(payload)


def pool_unit(payload: dict, *, study_workers: int = 1) -> dict:
    """``fake_unit``'s rows from the real sampling study on a synthetic scene (no render), on
    ``study_workers`` forked processes as a real unit's study: the pool's faults are real."""
    from simlunar.study.sampling import SamplingStudyOptions, run_sampling_study

    cfg = ExperimentCfg.model_validate(payload["config"])
    enter_unit(payload)
    s = cfg.study
    seeds = stage_seeds(cfg.seed)
    rng = np.random.default_rng(seeds["terrain"])
    shift = getattr(cfg.render.light, "elevation_deg", 45.0) / 90.0
    depth = np.cumsum(np.cumsum(rng.normal(size=(96, 96)), 0), 1) * 0.01
    image = np.abs(np.gradient(depth)[0]) * (1 + shift)
    opts = SamplingStudyOptions(
        strategies=list(s.strategies),
        densities=list(s.densities),
        trials=s.trials,
        metrics=list(s.metrics),
    )
    res = run_sampling_study(depth, image, opts, rng=seeds["study"], workers=study_workers)
    img = image.astype(np.float32)
    return {
        "rows": res.rows,
        "scores": {m: {k: float(v) for k, v in d.items()} for m, d in res.scores.items()},
        "timings": {"study_s": 0.0},
        "arrays": {
            "image": img,
            "depth": depth,
            "wavelet_energy": img**2,
            "plan_rows": np.arange(8, dtype=np.int32),
            "plan_cols": np.arange(8, dtype=np.int32),
            "reconstruction": depth * 1.01,
        },
        "meta": {"variant": "fake"},
    }
