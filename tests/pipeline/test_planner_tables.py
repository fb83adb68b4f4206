"""scores.md of a sampling run with the Lloyd-placement planners: samples saved vs Uniform Lloyd,
headroom captured vs the oracle, interior-only rows, rounds of multi-round labels."""

from __future__ import annotations

import json

import numpy as np

from simlunar.config import translate
from simlunar.config.schema import ExperimentCfg
from simlunar.pipeline.runner import run_experiment
from simlunar.pipeline.unit import stage_seeds, terrain_seed_sequence
from simlunar.results.figures import write_figures
from simlunar.study.sampling import run_sampling_study


def synthetic_unit(payload: dict) -> dict:
    """The real study (options translated from the YAML) on a synthetic scene per seed."""
    cfg = ExperimentCfg.model_validate(payload["config"])
    rng = np.random.default_rng(terrain_seed_sequence(cfg.seed, cfg.terrain.seed_index))
    y, x = np.mgrid[0:40, 0:56] / 14.0
    phase = rng.uniform(0, 3, size=2)
    depth = np.sin(3 * x + phase[0]) * np.cos(2 * y + phase[1]) + 0.1 * x
    image = (0.5 + 0.4 * np.sin(3 * x + phase[0] + 0.3)).astype(np.float32)
    res = run_sampling_study(
        depth, image, translate.sampling_options(cfg.study), rng=stage_seeds(cfg.seed)["study"]
    )
    return {
        "rows": res.rows,
        "scores": {m: {k: float(v) for k, v in d.items()} for m, d in res.scores.items()},
        "timings": {"study_s": 0.0},
        "arrays": {"image": image, "depth": depth},
        "meta": {"variant": "fake", "shape": list(depth.shape),
                 "rounds": {s: r.mean(axis=1).tolist() for s, r in res.rounds.items()}},
    }  # fmt: skip


def _run_two_seeds(tmp_path, strategies: list[str], **study) -> str:
    """scores.md of a 2-seed study of ``strategies`` (wavelet_lloyd: the wavelet map placed by
    Lloyd) on the synthetic scenes."""
    options = {"wavelet_lloyd": {"strategy": "wavelet", "placement": "lloyd"},
               **study.pop("strategy_options", {})}  # fmt: skip
    cfg = ExperimentCfg.model_validate(
        {"name": "planners", "seed": 3, "terrain": {"preset": "aerial_1", "scale": 0.125},
         "study": {"strategies": strategies, "strategy_options": options,
                   "densities": {"from": "1/4", "to": "1/32", "count": 4}, "metrics": ["mse"],
                   "terrain_seeds": 2, **study}}
    )  # fmt: skip
    run_experiment(cfg, tmp_path / "run", compute=synthetic_unit, progress=False, figures=False)
    return (tmp_path / "run" / "scores.md").read_text()


def test_scores_md_has_the_uniform_lloyd_headroom_and_interior_tables(tmp_path):
    md = _run_two_seeds(
        tmp_path,
        ["random", "grid", "lloyd_uniform", "wavelet_lloyd", "sequential", "oracle_greedy"],
        strategy_options={"sequential": {"sequential": {"max_rounds": 4}}},
        trials=2,
        score_region="both",
    )
    out = tmp_path / "run"
    assert "samples saved vs Grid at equal MSE" in md
    assert "| MSE (interior only) |" in md
    assert "samples saved vs Uniform Lloyd at equal MSE" in md
    assert "samples saved vs Uniform Lloyd at equal MSE (interior only)" in md
    assert "headroom captured vs Oracle greedy (true error) at equal MSE (2 terrain seeds)" in md
    grid_table = md.split("samples saved vs Grid at equal MSE\n")[1].split("###")[0]
    assert "| Oracle greedy (true error) |" in grid_table and "| Wavelet, Lloyd |" in grid_table
    head = md.split("headroom captured vs")[1]
    assert "| Oracle greedy (true error) |" in head and "1 (bound)" in head
    assert "| Sequential |" in head and "| Grid |" in head
    assert "paired by seed (2 terrain seeds)" not in md  # the headroom table holds those numbers
    rows = (out / "results.csv").read_text()
    assert ",mse_interior," in rows and ",mse," in rows
    metas = [json.loads(p.read_text())["meta"] for p in (out / "units").glob("*.json")]
    assert len(metas) == 2
    assert all(min(m["rounds"]["sequential"]) >= 2 for m in metas)
    # the study has an oracle and the uniform layout: the folder gets the headroom figure
    written = write_figures(out)
    assert out / "figures" / "headroom.png" in written
    captions = (out / "figures" / "captions.md").read_text()
    assert "## headroom" in captions and "cannot be realised" in captions


def test_without_an_oracle_scores_md_still_pairs_the_layouts_by_seed(tmp_path):
    md = _run_two_seeds(tmp_path, ["grid", "lloyd_uniform", "wavelet_lloyd"], trials=1)
    assert "headroom captured" not in md
    table = md.split(
        "samples saved vs Uniform Lloyd at equal MSE, paired by seed (2 terrain seeds)"
    )[1]
    assert "| Wavelet, Lloyd |" in table and "| Grid |" in table
    assert "| Uniform Lloyd |" not in table  # the reference is 1 by definition
