"""Measured check of the learned importance map and sequential refinement (not a test, no timing).

Quarter-scale aerial_1, aerial_3 and moonyard: render guide images and truth for terrain seeds
(the unit of work's render path), train one learned map on the training seeds of all three
presets, and measure on held-out seeds the samples saved at equal MSE against the uniform Lloyd
layout (paired: the same seeds), for the wavelet map placed with Lloyd, the learned map placed
with Lloyd, and sequential refinement (with no prior, the wavelet prior and the learned prior).

    PYTHONPATH=. python benchmarks/learned_check.py --out /tmp/learned_check

Uses ``simlunar.pipeline.unit``'s render helpers as of the redesign's first step; adapt the
import when the unit of work moves.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from simlunar.config.loading import validate_data
from simlunar.features import feature_map
from simlunar.features.learned import LearnedMap, LearnedOptions
from simlunar.metrics import samples_for_equal_error
from simlunar.pipeline.unit import (
    fill_invalid,
    int_seed,
    luminance,
    scene_inputs,
    sensor_image,
    stage_seeds,
)
from simlunar.planner.learning import train_learned_map
from simlunar.planner.placement import density_from_map, place
from simlunar.planner.sequential import SequentialOptions, plan_sequential
from simlunar.reconstruction import reconstruct
from simlunar.render import render

SCENES = {
    "aerial_1": {"altitude_m": 50, "elevation_deg": 30},
    "aerial_3": {"altitude_m": 50, "elevation_deg": 30},
    "moonyard": {"altitude_m": 3, "elevation_deg": 75},
}
DENSITIES = [2.0**-i for i in range(4, 11)]  # 1/16 .. 1/1024


def _cfg(preset: str, seed_index: int, scale: float):
    s = SCENES[preset]
    data = {
        "name": f"{preset}_{seed_index}",
        "seed": 1,
        "terrain": {"preset": preset, "scale": scale, "seed_index": seed_index},
        "render": {
            "camera": {"kind": "orthographic_nadir", "altitude_m": s["altitude_m"]},
            "light": {"kind": "sun", "elevation_deg": s["elevation_deg"], "azimuth_deg": 135},
            "bsdf": {"kind": "oren_nayar", "sigma_deg": 20},
            "spp": 16,
            "max_depth": 3,
            "sensor": {"full_well_e": 20000, "read_noise_e": 5, "bits": 12},
        },
        "study": {"kind": "sampling", "strategies": ["random"], "densities": [0.1]},
    }
    return validate_data(data, base_dir=Path("experiments"))


def guide_and_truth(preset: str, seed_index: int, scale: float, cache: Path):
    """(image float32, depth float64) of one terrain realisation, cached as npz."""
    path = cache / f"{preset}_{seed_index}_{scale:g}.npz"
    if path.is_file():
        z = np.load(path)
        return z["image"], z["depth"]
    cfg = _cfg(preset, seed_index, scale)
    seeds = stage_seeds(cfg.seed)
    terrain, camera, lights, bsdf = scene_inputs(cfg)
    r = cfg.render
    res = render(
        terrain,
        camera,
        lights=lights,
        bsdf=bsdf,
        spp=r.spp,
        seed=int_seed(seeds["render"]),
        max_depth=r.max_depth,
    )
    image = sensor_image(luminance(res.image), r.sensor, rng=np.random.default_rng(seeds["sensor"]))
    depth, _ = fill_invalid(np.where(res.gt.valid, res.gt.depth, np.nan))
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez(path, image=image, depth=depth)
    return image, depth


def _mse(flat, depth):
    r, c = np.divmod(flat, depth.shape[1])
    rec = reconstruct(np.column_stack((r, c)), depth[r, c], depth.shape)
    return float(np.mean((rec - depth) ** 2))


def evaluate(image, depth, model: LearnedMap, *, trials: int, seed: int) -> dict:
    """strategy -> MSE, float64 (densities, trials)."""
    n = depth.size
    wav = feature_map("wavelet", image)
    names = ["uniform", "wavelet", "learned", "seq", "seq_wavelet", "seq_learned"]
    out = {s: np.zeros((len(DENSITIES), trials)) for s in names}
    for i, d in enumerate(DENSITIES):
        k = round(d * n)
        lrn = model.predict(image, density=d)
        dens = {
            "uniform": np.ones(depth.shape),
            "wavelet": density_from_map(wav, power=0.5, mix=0.25),
            "learned": density_from_map(lrn, power=0.5, mix=0.25),
        }
        for t in range(trials):
            rng = np.random.default_rng([seed, i, t])
            for s, dm in dens.items():
                out[s][i, t] = _mse(place(dm, k, rng=rng), depth)
            for s, prior in (("seq", None), ("seq_wavelet", wav), ("seq_learned", lrn)):
                sp = plan_sequential(
                    k,
                    shape=depth.shape,
                    prior=prior,
                    rng=rng,
                    measure=lambda rc: depth[rc[:, 0], rc[:, 1]],
                    options=SequentialOptions(),
                )
                out[s][i, t] = _mse(sp.plan.flat, depth)
                out.setdefault(s + "_rounds", []).append(sp.rounds)
    return out


def saved_vs_uniform(errors: dict) -> dict:
    """Geometric mean over densities of (samples of uniform) / (samples of s) at equal MSE."""
    ks = [round(d * 1e6) for d in DENSITIES]  # any increasing proxy of k: ratios only
    errs = {s: v for s, v in errors.items() if not s.endswith("_rounds")}
    ratios = samples_for_equal_error(errs, ks, reference="uniform")
    return {s: float(np.exp(-np.nanmean(np.log(r)))) for s, r in ratios.items()}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=Path("/tmp/learned_check"))
    ap.add_argument("--scale", type=float, default=0.25)
    ap.add_argument("--train-seeds", type=int, default=4)
    ap.add_argument("--test-seeds", type=int, default=3)
    ap.add_argument("--trials", type=int, default=2)
    ap.add_argument("--presets", nargs="+", default=list(SCENES))
    a = ap.parse_args()
    cache = a.out / "renders"
    t = time.perf_counter()
    train = [guide_and_truth(p, s, a.scale, cache) for p in a.presets for s in range(a.train_seeds)]
    test = {
        p: [
            guide_and_truth(p, s, a.scale, cache)
            for s in range(a.train_seeds, a.train_seeds + a.test_seeds)
        ]
        for p in a.presets
    }
    report = {"render_s": time.perf_counter() - t, "shape": list(train[0][0].shape)}
    print("rendered", report, flush=True)
    t = time.perf_counter()
    model = train_learned_map(
        train,
        densities=DENSITIES,
        options=LearnedOptions(),
        rng=0,
        provenance={
            "presets": a.presets,
            "scale": a.scale,
            "train_seed_indices": list(range(a.train_seeds)),
        },
    )
    report["train_s"] = time.perf_counter() - t
    print("trained", report["train_s"], flush=True)
    model.save(a.out / "learned.joblib")
    for p, pairs in test.items():
        errs = {}
        for j, (img, z) in enumerate(pairs):
            e = evaluate(img, z, model, trials=a.trials, seed=j)
            for s, v in e.items():
                errs.setdefault(s, []).append(v)
        rounds = {
            s: [int(x) for v in errs.pop(s) for x in v] for s in list(errs) if s.endswith("_rounds")
        }
        per_seed = [saved_vs_uniform({s: v[j] for s, v in errs.items()}) for j in range(len(pairs))]
        report[p] = {
            "saved_vs_uniform": {
                s: float(np.exp(np.mean([np.log(x[s]) for x in per_seed]))) for s in per_seed[0]
            },
            "per_seed": per_seed,
            "rounds": {s: [min(v), max(v)] for s, v in rounds.items()},
        }
        print(p, json.dumps(report[p]["saved_vs_uniform"]), report[p]["rounds"], flush=True)
    report["total_s"] = time.perf_counter() - t
    (a.out / "report.json").write_text(json.dumps(report, indent=2))
    print(json.dumps({k: v for k, v in report.items() if k.endswith("_s")}))


if __name__ == "__main__":
    main()
