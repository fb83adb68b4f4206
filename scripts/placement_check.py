"""Measured check of the halftone + Lloyd placement (not a test): samples saved at equal MSE.

Quarter-scale presets, terrain seeds 0-2, densities 1/16 ... 1/2048, the project's own ``plan``,
``reconstruct`` and ``metric``. The guide image is an overhead Lambert hillshade of the heights
times the albedo (sun 30 deg up, azimuth 45 deg, no shadows), not a Mitsuba render, and the depth
is the heights (a nadir orthographic view). Prints and writes JSON: samples saved vs the
shifted grid and vs the uniform Lloyd layout (paired by seed), full image and interior only.

    PYTHONPATH=. python scripts/placement_check.py aerial_1,aerial_3,moonyard --trials 2
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from simlunar.features import feature_map
from simlunar.metrics import interior_mask, metric, samples_for_equal_error, sparsest_pitch
from simlunar.planner import plan
from simlunar.reconstruction import reconstruct
from simlunar.terrain.generate import generate

DENSITIES = [2.0**-e for e in range(4, 12)]
STRATEGIES = {
    "grid": ("grid", {}),
    "wavelet_random": ("wavelet", {}),
    "lloyd_uniform": ("lloyd_uniform", {}),
    "wavelet_lloyd": ("wavelet", {"placement": "lloyd"}),
    "oracle_greedy": ("oracle_greedy", {}),
    "oracle_hessian": ("oracle_hessian", {}),
}


def scene(preset: str, seed: int, scale: float):
    """Heights (m) and a hillshade guide image of a generated preset terrain."""
    t = generate(preset, rng=seed, scale=scale).terrain
    h = t.heights
    gy, gx = np.gradient(h, t.spacing)
    el, az = np.radians(30.0), np.radians(45.0)
    sun = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    n = np.stack([-gx, gy, np.ones_like(h)], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return h, (np.asarray(t.albedo, float) * np.clip(n @ sun, 0, None)).astype(np.float32)


def errors(depth, image, trials: int, seed: int):
    """Mean MSE per strategy and density, full image and interior: dicts of (n,) arrays."""
    mask = interior_mask(depth.shape, sparsest_pitch(depth.shape, DENSITIES))
    w = feature_map("wavelet", image)
    ks = [round(d * depth.size) for d in DENSITIES]
    full, inner = {}, {}
    for name, (s, o) in STRATEGIES.items():
        n_tr = 1 if s == "oracle_greedy" else trials  # deterministic
        e = np.zeros((2, len(ks), n_tr))
        for tr in range(n_tr):
            for i, k in enumerate(ks):
                p = plan(
                    s, k, weights=w if s == "wavelet" else None, shape=depth.shape,
                    truth=depth if s.startswith("oracle") else None,
                    rng=1000 * seed + 10 * tr + i, **o,
                )  # fmt: skip
                rec = reconstruct(p.rc, depth[p.rows, p.cols], depth.shape)
                e[0, i, tr] = metric("mse", rec, depth)
                e[1, i, tr] = metric("mse", rec, depth, mask=mask)
        full[name], inner[name] = e[0].mean(1), e[1].mean(1)
    return ks, full, inner


def saved(per_seed: list[dict], ks, reference: str) -> dict[str, float]:
    """Geometric-mean samples saved vs ``reference``, paired by seed."""
    out = {}
    for name in STRATEGIES:
        logs = []
        for e in per_seed:
            r = samples_for_equal_error({name: e[name], "_ref": e[reference]}, ks, "_ref")
            logs.append(np.nanmean(np.log(r[name])))
        out[name] = round(float(np.exp(-np.mean(logs))), 3)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("presets", help="comma-separated preset names")
    ap.add_argument("--trials", type=int, default=2)
    ap.add_argument("--scale", type=float, default=0.25)
    ap.add_argument("--out", default="build/placement_check.json")
    args = ap.parse_args(argv)
    result = {}
    for preset in args.presets.split(","):
        t0 = time.perf_counter()
        runs = [errors(*scene(preset, s, args.scale), args.trials, s) for s in range(3)]
        ks = runs[0][0]
        res = {}
        for tag, idx in (("full", 1), ("interior", 2)):
            for ref in ("grid", "lloyd_uniform"):
                res[f"{tag}_saved_vs_{ref}"] = saved([r[idx] for r in runs], ks, ref)
        res["seconds"] = round(time.perf_counter() - t0, 1)
        result[preset] = res
        print(preset, json.dumps(res, indent=1), flush=True)
    with open(args.out, "w") as f:
        json.dump(result, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
