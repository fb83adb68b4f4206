"""Repeats over terrain seeds: units, seeds, cache keys, results columns, pooled tables."""

from __future__ import annotations

import csv
import io

import numpy as np
import pytest
from fake_unit import fake_unit

from simlunar.config.schema import ExperimentCfg
from simlunar.pipeline.runner import expand, run_experiment
from simlunar.pipeline.unit import stage_seeds, terrain_seed_sequence
from simlunar.results import aggregate


def cfg(n_seeds=1, **over) -> ExperimentCfg:
    d = {
        "name": "seeds_test",
        "seed": 7,
        "terrain": {"preset": "aerial_1", "scale": 0.125},
        "study": {
            "strategies": ["random", "grid", "wavelet"],
            "densities": {"from": "1/2", "to": "1/32", "count": 5},
            "trials": 3,
            "metrics": ["mse", "grad"],
            "terrain_seeds": n_seeds,
        },
        "sweep": {"render.light.elevation_deg": [10, 60]},
    }
    d.update(over)
    return ExperimentCfg.model_validate(d)


def test_terrain_seed_sequences():
    # index 0 is the terrain stage's own stream (runs without terrain_seeds keep their
    # terrain); index i is the stage's child i - 1, distinct for every i
    s0 = terrain_seed_sequence(5, 0).generate_state(4)
    assert np.array_equal(s0, stage_seeds(5)["terrain"].generate_state(4))
    child = stage_seeds(5)["terrain"].spawn(3)[2].generate_state(4)
    assert np.array_equal(terrain_seed_sequence(5, 3).generate_state(4), child)
    states = {tuple(terrain_seed_sequence(5, i).generate_state(4)) for i in range(6)}
    assert len(states) == 6
    with pytest.raises(ValueError):
        terrain_seed_sequence(5, -1)


@pytest.mark.parametrize("kind", ["scene", "experiment"])
def test_seed_index_gives_another_terrain_and_zero_the_old_one(kind):
    # both the scene path (simlunar render) and the experiment path (the units of simlunar
    # run) must build realisation i from terrain_seed_sequence(seed, i)
    from simlunar.config.scene import SceneCfg
    from simlunar.pipeline.unit import scene_inputs

    def terrain(seed_index=None):
        t = {"preset": "aerial_1", "scale": 0.0625}
        if seed_index is not None:
            t["seed_index"] = seed_index
        if kind == "scene":
            return scene_inputs(SceneCfg.model_validate({"terrain": t, "seed": 3}))[0]
        return scene_inputs(cfg(terrain=t, seed=3))[0]

    t0, t0b, t1, t1b = terrain(), terrain(0), terrain(1), terrain(1)
    assert np.array_equal(t0.heights, t0b.heights)
    assert np.array_equal(t1.heights, t1b.heights)
    assert t1.heights.shape == t0.heights.shape
    assert not np.allclose(t1.heights, t0.heights)


def test_expand_repeats_every_point_over_the_seeds():
    units = expand(cfg(3))
    assert len(units) == 6
    assert [u.terrain_seed for u in units] == [0, 1, 2, 0, 1, 2]
    assert [u.config["terrain"]["seed_index"] for u in units] == [0, 1, 2, 0, 1, 2]
    assert [u.index for u in units] == list(range(6))
    assert len({u.key for u in units}) == 6
    # seed 0 of a repeated run is the unit of the run without repeats (cache shared)
    plain = expand(cfg(1))
    assert [u.terrain_seed for u in plain] == [None, None]
    assert units[0].key == plain[0].key and units[3].key == plain[1].key
    # the other config fields are shared
    assert units[1].config["render"] == units[0].config["render"]


def test_seed_index_is_for_presets_only(tmp_path):
    from pydantic import ValidationError

    with pytest.raises(ValidationError, match="seed_index"):
        ExperimentCfg.model_validate(
            {
                "name": "x",
                "terrain": {"file": str(tmp_path / "a.npy"), "spacing_m": 1, "seed_index": 1},
                "study": {"densities": [0.5]},
            }
        )


def test_a_dem_with_rocks_draws_its_rocks_per_terrain_seed(tmp_path):
    # a flat 40 x 40 m DEM of 1 m cells, refined to 0.1 m and given Golombek rocks (k = 0.07):
    # seed 0 and seed 1 stamp different rocks on the same surface, seed 0 twice the same;
    # without rocks seed_index stays refused (above)
    from simlunar.pipeline.unit import scene_inputs

    dem = tmp_path / "site.npy"
    np.save(dem, np.zeros((40, 40)))
    terrain = {"file": str(dem), "spacing_m": 1.0, "refine_m": 0.1,
               "rocks": {"law": "golombek", "coefficient": 0.07, "d_min_m": 0.2, "d_max_m": 2.0}}  # fmt: skip

    def build(i):
        c = ExperimentCfg.model_validate({"name": "x", "seed": 3, "study": {"densities": [0.5]},
                                          "terrain": {**terrain, "seed_index": i}})  # fmt: skip
        return scene_inputs(c)[0]

    a, b, again = build(0), build(1), build(0)
    assert a.shape == (400, 400) and a.spacing == pytest.approx(0.1)
    assert np.array_equal(a.heights, again.heights)
    assert not np.array_equal(a.heights, b.heights)
    # rocks stand on the flat DEM: every raised cell is a rock's, none below the DEM
    assert a.heights.min() == 0.0 and 0.3 < a.heights.max() < 2.0
    assert 0.005 < (a.heights > 0.05).mean() < 0.2


def _run(c, out):
    return run_experiment(c, out, compute=fake_unit, progress=False, figures=False)


def test_results_keep_per_seed_rows_and_tables_pool_them(tmp_path):
    _run(cfg(1), tmp_path / "one")
    one = (tmp_path / "one" / "results.csv").read_text()
    assert one.splitlines()[0] == (
        "unit,render.light.elevation_deg,strategy,reconstruction,density,k,trial,metric,value"
    )
    _run(cfg(3), tmp_path / "three")
    rows = list(csv.DictReader(io.StringIO((tmp_path / "three" / "results.csv").read_text())))
    assert list(rows[0])[:3] == ["unit", "render.light.elevation_deg", "terrain_seed"]
    assert {(r["unit"], r["terrain_seed"]) for r in rows} == {
        (str(i), str(i % 3)) for i in range(6)
    }
    assert len(rows) == 6 * 3 * 5 * 3 * 2
    md = (tmp_path / "three" / "scores.md").read_text()
    assert "Scores pool 3 terrain seed(s) x 3 trials" in md
    assert "| MSE | 1.00 [1.00, 1.00] |" in md
    assert "samples saved vs Random at equal MSE" in md
    assert "samples saved vs Grid at equal MSE" in md
    scores = list(csv.DictReader(io.StringIO((tmp_path / "three" / "scores.csv").read_text())))
    seeds = {r["terrain_seed"] for r in scores}
    assert seeds == {"0", "1", "2", "all"}
    pooled = [r for r in scores if r["terrain_seed"] == "all"]
    assert len(pooled) == 2 * 2 * 3  # points x metrics x strategies
    assert all(float(r["ci_low"]) <= float(r["score"]) <= float(r["ci_high"]) for r in pooled)


def test_pooled_score_is_eq_4_3_of_all_pairs(tmp_path):
    from simlunar.metrics import score

    _run(cfg(2, sweep={}), tmp_path / "r")
    rows = list(csv.DictReader(io.StringIO((tmp_path / "r" / "results.csv").read_text())))
    recs = [{"sweep": u.sweep, "config": u.config} for u in expand(cfg(2, sweep={}))]
    (point,) = aggregate.group_points(recs)
    assert point.seeds == [0, 1] and point.unit_indices == [0, 1]
    dens, _ks, errs = aggregate.error_arrays(rows, point, "mse")
    assert errs["random"].shape == (2, 5, 3)
    # pooled over seeds = eq. 4.3 of the errors with seeds and trials side by side
    flat = {s: e.transpose(1, 0, 2).reshape(5, 6) for s, e in errs.items()}
    want = score(flat, dens)
    (p,) = aggregate.summarise(recs, rows, seed=7, n_boot=50)
    assert p.intervals["mse"].score == pytest.approx([want[s] for s in p.strategies])


def test_a_sweep_over_seed_index_is_pooled_too():
    units = expand(cfg(1, sweep={"terrain.seed_index": [0, 1, 2]}))
    recs = [{"sweep": u.sweep, "config": u.config} for u in units]
    (point,) = aggregate.group_points(recs)
    assert point.seeds == [0, 1, 2]


def test_figure_titles_name_the_terrain_seed():
    # panels of a repeated experiment say which terrain realisation they show
    from simlunar.results.sampling_figures import _label

    rec = {"index": 3, "key": "k", "sweep": {}, "config": cfg(3).model_dump(mode="json")}
    rec["config"]["terrain"]["seed_index"] = 2
    assert "terrain seed 2" in _label(rec)
    single = {"index": 0, "key": "k", "sweep": {}, "config": cfg(1).model_dump(mode="json")}
    assert "terrain_seed" not in _label(single)


def test_error_vs_density_draws_one_pooled_panel_per_sweep_point(tmp_path, monkeypatch):
    # 2 sweep points x 3 terrain seeds: two panels (not six), each pooling its three units,
    # with the band and caption saying so
    from simlunar.plotting import figures as F
    from simlunar.results import figures as PF
    from simlunar.results.aggregate import density_panels

    units = [
        {"index": u.index, "key": u.key, "sweep": u.sweep, "config": u.config}
        for u in expand(cfg(3))
    ]
    panels = density_panels(units)
    assert [t for t, _ in panels] == ["sun elevation: 10°", "sun elevation: 60°"]
    assert [[r["index"] for r in members] for _, members in panels] == [[0, 1, 2], [3, 4, 5]]

    _run(cfg(3), tmp_path / "r")
    drawn = []
    real = F.error_vs_density

    def spy(rows, **kw):
        drawn.append((kw["where"], kw["band_label"]))
        return real(rows, **kw)

    monkeypatch.setattr(F, "error_vs_density", spy)
    PF.write_figures(tmp_path / "r")
    # every reconstruction on the panel (a line style each), not only the first
    assert drawn[:2] == [
        ({"unit": [0, 1, 2]}, F.BAND_LABEL_SEEDS),
        ({"unit": [3, 4, 5]}, F.BAND_LABEL_SEEDS),
    ]
    assert len(drawn) == 2 * 2  # two panels per metric, two metrics
    text = (tmp_path / "r" / "figures" / "captions.md").read_text()
    assert "mean over 3 terrain seeds × 3 trials" in text


def test_scanner_ablation_axis_of_the_sun_to_projector_ratio():
    # the top axis appears only when ambient_ratio is proportional to the swept irradiance
    from simlunar.results.scanner_figures import _ambient_axis

    units = [{"index": i, "sweep": {"render.light.irradiance": x}} for i, x in enumerate([1, 10])]
    rows = [
        {"unit": "0", "metric": "ambient_ratio", "value": "0.24"},
        {"unit": "1", "metric": "ambient_ratio", "value": "2.4"},
    ]
    k, text = _ambient_axis(rows, units, "render.light.irradiance")
    assert k == pytest.approx(0.24) and "sun / projector" in text
    rows[1]["value"] = "3.0"  # not proportional: no axis
    assert _ambient_axis(rows, units, "render.light.irradiance") is None
    assert _ambient_axis(rows[:1], units, "render.light.irradiance") is None  # a dark unit
