"""Terrain benchmarks: generate aerial_1 at full size; cost scaling with the number of cells.

terrain_aerial: ``ours_s`` = median wall time of ``generate(preset_params("aerial_1"))`` (1000 x 1600 cells,
0.2 m) over 3 seeds after one warm-up (the crater degradation table is built once per process).
There is no reference implementation, so ``reference_s`` is None (target: under 3 s on 2 cores).

scaling: time of the full grid over the time of a 1/4-size grid (``scale=0.5``: half the rows
and columns, same spacing, so a quarter of the cells, craters and rocks); about 4 if the cost is
linear in cells.
"""

from __future__ import annotations

import statistics
import time


def _time_generate(name: str, scale: float, seeds) -> float:
    from simlunar.config.translate import preset_params
    from simlunar.terrain import generate

    times = []
    for s in seeds:
        t0 = time.perf_counter()
        generate(preset_params(name), rng=s, scale=scale)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


#: ``smoke=True``: the grid scale of the "full" size (the same code at a tiny size)
SMOKE_SCALE = 0.05


def bench_terrain_aerial(*, smoke: bool = False) -> dict:
    from simlunar.config.translate import preset_params
    from simlunar.terrain import generate

    scale = SMOKE_SCALE if smoke else 1.0
    generate(preset_params("aerial_1"), rng=0, scale=0.1 * scale)  # warm-up: the crater table
    res = generate(preset_params("aerial_1"), rng=1, scale=scale)
    ours = _time_generate("aerial_1", scale, seeds=(1,) if smoke else (1, 2, 3))
    rows, cols = res.terrain.shape
    return {
        "reference_s": None,
        "ours_s": round(ours, 3),
        "smoke": smoke,
        "cells": rows * cols,
        "craters": len(res.craters),
        "rocks": len(res.rocks),
        "target_s": 3.0,
    }


def bench_scaling(*, smoke: bool = False) -> dict:
    from simlunar.config.translate import preset_params
    from simlunar.terrain import generate

    scale, seeds = (SMOKE_SCALE, (1,)) if smoke else (1.0, (1, 2, 3))
    generate(preset_params("aerial_1"), rng=0, scale=0.1 * scale)
    full = _time_generate("aerial_1", scale, seeds=seeds)
    quarter = _time_generate("aerial_1", 0.5 * scale, seeds=seeds)
    return {
        "reference_s": None,
        "ours_s": round(full, 3),
        "smoke": smoke,
        "quarter_s": round(quarter, 3),
        "time_ratio_full_over_quarter": round(full / quarter, 2),
        "cells_ratio": 4.0,
    }


BENCHMARKS = {"terrain_aerial": bench_terrain_aerial, "scaling": bench_scaling}
