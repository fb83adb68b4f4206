"""Preset roughness beside published lunar values (docs/terrain.md has the sources).

roughness_<preset>: each preset generated at full size (seed 0) and measured with
``simlunar.terrain.stats.roughness`` at 1, 4 and 16 cells (0.2, 0.8, 3.2 m for the aerial presets;
1.2, 4.8, 19.2 mm for the moonyard). ``reference_s`` is the time to generate the terrain and
``ours_s`` the time of the statistics (five baselines), so the ratio says how many statistics
runs fit in one generation. Printed beside each: the published Hurst range for its scale
(metre scale: Cai & Fa 2020, JGR Planets, 0.7-0.95, median 0.9; millimetre scale: Guo et al.
2021, GRL, about 0.6-0.85) and whether the preset's H lies inside it.
"""

from __future__ import annotations

import time

PUBLISHED = {
    "m": ((0.70, 0.95), "Cai & Fa 2020 (LROC NAC DTMs, m-hm baselines)"),
    "mm": ((0.60, 0.85), "Guo et al. 2021 (Chang'E-4, mm-dm baselines)"),
}


def _one(name: str, scale: float = 1.0) -> dict:
    from simlunar.config.translate import preset_params
    from simlunar.terrain import generate
    from simlunar.terrain.stats import roughness

    t0 = time.perf_counter()
    t = generate(preset_params(name), rng=0, scale=scale).terrain
    gen = time.perf_counter() - t0
    t0 = time.perf_counter()
    r = roughness(t.heights, t.spacing)
    ours = time.perf_counter() - t0
    (lo, hi), src = PUBLISHED["mm" if t.spacing < 0.01 else "m"]
    fig = {"reference_s": round(gen, 3), "ours_s": round(ours, 3)}
    for i in (0, 2, 4):
        key = f"{r.baselines_m[i]:.4g}m"
        fig[f"rms_slope_deg_{key}"] = round(r.rms_slope_deg[i], 2)
        fig[f"median_slope_deg_{key}"] = round(r.median_slope_deg[i], 2)
    fig["hurst"] = round(r.hurst, 3)
    fig["published_hurst"] = f"{lo}-{hi} {src}"
    fig["hurst_in_range"] = bool(lo <= r.hurst <= hi)
    return fig


def bench_roughness(*, smoke: bool = False) -> dict:
    """One figure dict per preset (``smoke``: each preset at 1/10 of its rows and columns)."""
    from simlunar.config.translate import preset_params
    from simlunar.terrain import generate

    scale = 0.1 if smoke else 1.0
    generate(preset_params("aerial_1"), rng=0, scale=0.1 * scale)  # warm-up: the crater table
    names = ("aerial_1", "aerial_2", "aerial_3", "moonyard")
    return {f"roughness_{n}": {**_one(n, scale), "smoke": smoke} for n in names}


BENCHMARKS = {"roughness": bench_roughness}
