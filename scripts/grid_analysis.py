"""Why the shifted grid beats random sampling on simlunar's terrains (REPRODUCTION.md).

    python scripts/grid_analysis.py RESULT_DIR [RESULT_DIR ...]   # finished sampling runs
    python scripts/grid_analysis.py --fields                      # Gaussian random fields

For each sweep point of a result folder (pooled over its terrain seeds): the grid's
per-density lead over random (mean random MSE / mean grid MSE) and, per terrain seed, the share
of the height variance at wavelengths longer than twice the sparsest sample pitch
(``simlunar.study.spectrum.variance_share_above`` on the unit's cached height grid). With
``--fields``: the random/grid MSE ratio on unit-variance Gaussian random fields of growing
correlation length at one density.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np


def results_report(out_dir: str) -> None:
    from simlunar.results import aggregate
    from simlunar.results.figures import load_results
    from simlunar.results.store import UnitCache
    from simlunar.study.spectrum import sample_pitch, variance_share_above

    res = load_results(out_dir)
    cache = UnitCache(res["dir"])
    points = aggregate.summarise(res["units"], res["rows"], seed=0, n_boot=10)
    print(f"## {out_dir}")
    for p in points:
        if "grid" not in p.strategies or "mse" not in p.mean_errors:
            continue
        e = p.mean_errors["mse"]
        lead = e["random"] / e["grid"]
        cols = " ".join(f"1/{round(1 / d)}:{v:.2f}" for d, v in zip(p.densities, lead))
        print(f"{p.label}: random/grid MSE per density: {cols}")
        shares = []
        for j in p.unit_indices:
            rec = res["units"][j]
            heights = cache.load_arrays(rec["key"])["heights"]
            spacing = float((rec.get("meta") or {}).get("spacing_m", 1.0))
            lam = 2 * sample_pitch(min(p.densities)) * spacing
            shares.append(variance_share_above(heights, spacing=spacing, wavelength=lam))
        s = np.asarray(shares)
        print(
            f"{p.label}: variance share above 2 x pitch(1/{round(1 / min(p.densities))}) "
            f"= {lam:.3g} m: {s.mean():.3f} (seeds: {', '.join(f'{v:.3f}' for v in s)})"
        )


def fields_report(size: int = 256, density: float = 1 / 256, trials: int = 4) -> None:
    from simlunar.study.spectrum import gaussian_field, random_grid_mse_ratio, sample_pitch

    pitch = sample_pitch(density)
    print(f"## Gaussian random fields {size} x {size}, density 1/{round(1 / density)} "
          f"(pitch {pitch:.0f} cells), {trials} trials, 6 fields each")  # fmt: skip
    print("| correlation length (cells) | random / grid MSE |")
    print("|---:|---:|")
    for length in (0, 1, 2, 4, 8, 16, 32):
        r = [
            random_grid_mse_ratio(
                gaussian_field((size, size), length, rng=seed), density, trials=trials, rng=seed
            )
            for seed in range(6)
        ]
        print(f"| {length} | {np.mean(r):.2f} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", nargs="*", help="finished sampling result folders")
    ap.add_argument("--fields", action="store_true", help="the Gaussian random field sweep")
    args = ap.parse_args(argv)
    for d in args.results:
        results_report(d)
    if args.fields:
        fields_report()
    if not args.results and not args.fields:
        ap.print_usage(sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
