"""Run simlunar's benchmarks: ``make bench`` (all) or ``make bench ONLY=<name>``.

Each ``benchmarks/bench_*.py`` module defines ``BENCHMARKS``: a dict mapping a benchmark name
to a function returning a dict with at least ``reference_s`` and ``ours_s`` (seconds, measured
in the same run) and any counts. A benchmark with no reference path may return
``reference_s = None`` (then no ratio is printed, only its figures). For each benchmark this
prints ``<name>: <ratio>x`` (reference time / simlunar time) and writes
``build/bench.json`` mapping each name to its figures (merged with earlier runs).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE.parent / "build" / "bench.json"


def discover() -> dict:
    benches = {}
    for path in sorted(HERE.glob("bench_*.py")):
        spec = importlib.util.spec_from_file_location(path.stem, path)
        mod = importlib.util.module_from_spec(spec)
        assert spec.loader is not None
        spec.loader.exec_module(mod)
        for name, fn in getattr(mod, "BENCHMARKS", {}).items():
            if name in benches:
                raise SystemExit(f"duplicate benchmark name {name!r} in {path.name}")
            benches[name] = fn
    return benches


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--only", help="comma-separated benchmark names (or prefixes)")
    ap.add_argument("--list", action="store_true")
    args = ap.parse_args(argv)
    benches = discover()
    if args.list:
        print("\n".join(benches))
        return 0
    names = list(benches)
    if args.only:
        wanted = [w.strip() for w in args.only.split(",") if w.strip()]
        names = [n for n in names if any(n == w or n.startswith(w) for w in wanted)]
        if not names:
            print(
                f"no benchmark matches {args.only!r}; known: {', '.join(benches)}", file=sys.stderr
            )
            return 2
    try:
        results = json.loads(OUT.read_text())
    except (OSError, ValueError):
        results = {}
    failed = 0
    for name in names:
        t0 = time.perf_counter()
        try:
            res = benches[name]()
        except Exception as exc:  # report and go on with the other benchmarks
            print(f"{name}: FAILED ({type(exc).__name__}: {exc})", flush=True)
            failed += 1
            continue
        # a benchmark may return several named results (e.g. one per k)
        items = res.items() if all(isinstance(v, dict) for v in res.values()) else [(name, res)]
        for sub, fig in items:
            ref, ours = fig.get("reference_s"), fig.get("ours_s")
            if ref is not None and ours:
                fig["ratio"] = round(ref / ours, 3)
            fig["wall_s"] = round(time.perf_counter() - t0, 3)
            extras = ", ".join(
                f"{k}={v}"
                for k, v in fig.items()
                if k not in ("ratio",) and not isinstance(v, (dict, list))
            )
            ratio = f"{fig['ratio']}x" if "ratio" in fig else "n/a"
            print(f"{sub}: {ratio}  ({extras})", flush=True)
            results[sub] = fig
    OUT.parent.mkdir(parents=True, exist_ok=True)
    tmp = OUT.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps(results, indent=2, sort_keys=True))
    os.replace(tmp, OUT)
    print(f"wrote {OUT}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent))
    raise SystemExit(main())
