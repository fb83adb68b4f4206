"""Every experiment YAML shipped in experiments/ validates and expands into work units."""

from __future__ import annotations

from pathlib import Path

import pytest

from simlunar.config.loading import load_experiment
from simlunar.config.studies import SamplingStudyCfg
from simlunar.pipeline.runner import expand

EXPERIMENTS = sorted((Path(__file__).resolve().parents[2] / "experiments").glob("*.yaml"))


def test_the_expected_experiments_exist():
    names = {p.stem for p in EXPERIMENTS}
    assert {
        "quickstart",
        "table1_aerial",
        "table2_moonyard",
        "scanner_ambiguity",
        "ablation_sun_elevation",
        "ablation_sun_azimuth",
        "ablation_light",
        "ablation_brdf",
        "ablation_albedo",
        "ablation_sensor_noise",
    } <= names


@pytest.mark.parametrize("path", EXPERIMENTS, ids=[p.stem for p in EXPERIMENTS])
def test_experiment_validates(path, with_shipped_models):
    # the learned-map experiments hash their model files into the units' keys: a working
    # folder with model files of the same format stands in for `simlunar train`'s results
    cfg = load_experiment(path)
    assert cfg.name == path.stem
    units = expand(cfg)
    repeats = getattr(cfg.study, "terrain_seeds", 1)
    points = max(1, __import__("math").prod(len(v) for v in cfg.sweep.values()))
    assert len(units) == points * repeats
    assert len({u.key for u in units}) == len(units)


def test_fusion_experiments_protocol():
    # the full-resolution study of the reconstructions on the Tables' terrains (experiment
    # seeds 1 and 2, five realisations: no tuning saw them, it ran on quarter-scale
    # realisations, which are other terrains), 1/64 .. 1/2048 (6 densities), 1 trial, the
    # uniform Lloyd layout, linear with the image-free control beside every image-guided
    # reconstruction; under a sun, shading from the sun image alone and with the co-located frame
    fusion = [p for p in EXPERIMENTS if p.stem.startswith(("fusion_table", "fusion_camera"))]
    assert {p.stem for p in fusion} >= {
        "fusion_table1_aerial",
        "fusion_table1_aerial_sun60",
        "fusion_table2_moonyard",
        "fusion_camera_light",
    }
    for path in fusion:
        cfg = load_experiment(path)
        s = cfg.study
        assert cfg.seed == (2 if "moonyard" in path.stem else 1)
        assert s.densities == [2.0**-i for i in range(6, 12)]
        assert s.trials == 1 and s.terrain_seeds == 5
        assert "lloyd_uniform" in s.strategies
        names = [r if isinstance(r, str) else next(iter(r)) for r in s.reconstructions]
        assert names[:2] == ["linear", "smoothed"] and "shading" in names
        sun = cfg.render.light.kind == "sun"
        assert (cfg.render.guide_frames == ["camera"]) == sun
        assert ("shading_sun" in names) == sun
        assert getattr(cfg.terrain, "scale", 1.0) in (None, 1.0)  # full resolution


def test_paper_protocol_in_the_tables():
    # paper section 4.1: 11 densities 1/2 .. 1/2048, 20 trials, the five strategies, and
    # beside them the image-free uniform Lloyd reference and an oracle bound
    for name in ("table1_aerial", "table2_moonyard"):
        cfg = load_experiment(next(p for p in EXPERIMENTS if p.stem == name))
        assert isinstance(cfg.study, SamplingStudyCfg)
        assert cfg.study.densities == [2.0**-i for i in range(1, 12)]
        assert cfg.study.trials == 20
        assert {"random", "grid", "gradient", "entropy", "wavelet"} <= set(cfg.study.strategies)
        assert {"lloyd_uniform", "oracle_greedy"} <= set(cfg.study.strategies)
        assert cfg.study.terrain_seeds >= 5  # intervals over terrain realisations


def test_learned_quick_uses_the_model_its_training_yaml_writes(with_shipped_models):
    """experiments/learned_quick.yaml (README's quick learned path): its learned planner reads
    the model `simlunar train experiments/training/learned_quarter.yaml` writes, at that
    model's densities, beside the two Lloyd layouts it is compared with, on a preset the model
    held out."""
    from simlunar.config.training import load_training

    root = Path(__file__).resolve().parents[2]
    cfg = load_experiment(root / "experiments" / "learned_quick.yaml")
    train, _ = load_training(root / "experiments" / "training" / "learned_quarter.yaml")
    study = cfg.study
    assert {"lloyd_uniform", "wavelet_lloyd", "learned_lloyd"} <= set(study.strategies)
    opts = study.strategy_options["learned_lloyd"]
    assert opts.strategy == "learned" and opts.placement == "lloyd"
    assert opts.feature_opts.model == train.model
    assert sorted(study.densities) == sorted(train.densities)
    assert cfg.terrain.preset in train.held_out_presets
    for doc in ("README.md", "docs/experiments.md", "Makefile"):
        assert "learned_quick" in (root / doc).read_text(), doc
