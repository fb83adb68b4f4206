"""Every benchmark runs: each ``benchmarks/bench_*.py`` function with ``smoke=True``.

A benchmark is only run by ``make bench``, so one that stopped working (a renamed library
function, a changed frame count) used to go unseen until someone measured. Here every
benchmark the harness discovers (``benchmarks/run.py``) runs its own code path at a tiny size
and must return the harness's figures: ``reference_s`` (seconds, or None where there is no
reference path) and ``ours_s`` (seconds), for each named result when it returns several.
"""

from __future__ import annotations

import importlib.util
import inspect
import math
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH_DIR = ROOT / "benchmarks"


def _discover() -> dict:
    spec = importlib.util.spec_from_file_location("_bench_run", BENCH_DIR / "run.py")
    mod = importlib.util.module_from_spec(spec)
    assert spec.loader is not None
    if str(BENCH_DIR) not in sys.path:  # benchmarks import their helpers by module name
        sys.path.insert(0, str(BENCH_DIR))
    spec.loader.exec_module(mod)
    return mod.discover()


BENCHES = _discover()


def _figures(res: dict) -> dict:
    """name -> figures; a benchmark may return several named results (as run.py reads them)."""
    if res and all(isinstance(v, dict) for v in res.values()):
        return res
    return {"": res}


def test_every_benchmark_takes_smoke():
    assert len(BENCHES) >= 20
    for name, fn in BENCHES.items():
        p = inspect.signature(fn).parameters.get("smoke")
        assert p is not None, f"{name} has no smoke keyword"
        assert p.kind is inspect.Parameter.KEYWORD_ONLY and p.default is False, name


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(BENCHES))
def test_bench_smoke(name):
    res = BENCHES[name](smoke=True)
    assert isinstance(res, dict) and res
    for sub, fig in _figures(res).items():
        assert "ours_s" in fig and "reference_s" in fig, (name, sub, sorted(fig))
        assert isinstance(fig["ours_s"], float) and math.isfinite(fig["ours_s"])
        assert fig["ours_s"] >= 0.0
        ref = fig["reference_s"]
        assert ref is None or (isinstance(ref, float) and math.isfinite(ref) and ref >= 0.0)
