"""Measured check of the learned reconstruction (not a test, not a benchmark of speed).

Renders quarter-scale views of Table 1's aerial scenes as a unit renders them (the tables' seed
1; terrain realisations 4 and 5 of aerial_1 and aerial_3, 0 of the held-out aerial_2: none is a
training terrain of ``experiments/training/learned_recon_quarter.yaml``, seed 100), draws one
uniform Lloyd layout per density and reports, for the learned reconstruction against
Delaunay-linear on the same layout: the MSE ratio at 1/64 .. 1/2048, and the samples saved at
equal MSE (linear's MSE-vs-k curve at 19 densities 1/16 .. 1/4096, interpolated log-log, read at
the learned reconstruction's MSE: k_linear / k), with its geometric mean over the densities.

    simlunar train experiments/training/learned_recon_quarter.yaml
    PYTHONPATH=. python benchmarks/learned_recon_check.py \\
        --model models/learned_recon_quarter.joblib --out /tmp/learned_recon_check.json
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from simlunar.config.loading import load_experiment
from simlunar.pipeline.train import guide_view
from simlunar.planner.sequential import uniform_layout
from simlunar.reconstruction import Guide, reconstruct, run_reconstruction

ROOT = Path(__file__).resolve().parents[1]
VIEWS = [("aerial_1", 4), ("aerial_1", 5), ("aerial_3", 4), ("aerial_3", 5), ("aerial_2", 0)]
LINEAR_DENSITIES = [2.0**-e for e in np.arange(4, 13.01, 0.5)]
DENSITIES = [2.0**-e for e in range(6, 12)]


def _layout(z, density, seed=0):
    k = round(density * z.size)
    r, c = np.divmod(uniform_layout(z.shape, k, rng=seed), z.shape[1])
    return k, np.column_stack((r, c)), z[r, c]


def check(model: str, scale: float = 0.25) -> dict:
    exp = load_experiment(ROOT / "experiments" / "table1_aerial.yaml")
    out = {}
    for preset, idx in VIEWS:
        terrain = exp.terrain.model_copy(
            update={"preset": preset, "scale": scale, "seed_index": idx}
        )
        image, z = guide_view(exp.model_copy(update={"terrain": terrain, "sweep": {}}))
        curve = []
        for d in LINEAR_DENSITIES:
            k, pts, vals = _layout(z, d)
            curve.append((k, np.mean((reconstruct(pts, vals, z.shape) - z) ** 2)))
        lk, le = np.log(np.array(curve)).T
        order = np.argsort(le)
        ratios, saved, seconds = [], [], []
        for d in DENSITIES:
            k, pts, vals = _layout(z, d)
            lin = np.mean((reconstruct(pts, vals, z.shape) - z) ** 2)
            t = time.perf_counter()
            rec = run_reconstruction(
                "learned", pts, vals, z.shape, guide=Guide(image), options={"model": model}
            )
            seconds.append(time.perf_counter() - t)
            mse = np.mean((rec.heights - z) ** 2)
            ratios.append(float(lin / mse))
            if le.min() <= np.log(mse) <= le.max():
                saved.append(float(np.exp(np.interp(np.log(mse), le[order], lk[order])) / k))
        out[f"{preset}/{idx}"] = {
            "mse_ratio": [round(r, 3) for r in ratios],
            "samples_saved": [round(s, 3) for s in saved],
            "samples_saved_gmean": round(float(np.exp(np.mean(np.log(saved)))), 3),
            "reconstruction_s_median": round(float(np.median(seconds)), 2),
        }
        print(preset, idx, out[f"{preset}/{idx}"], flush=True)
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="models/learned_recon_quarter.joblib")
    ap.add_argument("--out", type=Path, default=Path("/tmp/learned_recon_check.json"))
    a = ap.parse_args()
    a.out.write_text(json.dumps(check(a.model), indent=1) + "\n")
