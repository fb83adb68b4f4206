"""The figures of a sampling result folder, on a hand-made folder: which figures are drawn
(density curves pooled per sweep point, each unit's panels, samples saved, scores against a
one-axis sweep), their captions, unit titles and cell sizes, a corrupt unit file named."""

from __future__ import annotations

import csv

import matplotlib.pyplot as plt
import numpy as np
import pytest

from simlunar.errors import ResultFolderError
from simlunar.results import sampling_figures as sf
from simlunar.results.captions import Captions

DENSITIES = [0.5, 0.25, 0.125]


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _rows(unit):
    out = []
    for s, scale in (("random", 1.0), ("wavelet", 0.5)):
        for d in DENSITIES:
            k = int(d * 256)
            for t in range(2):
                out.append({"unit": str(unit), "strategy": s, "density": str(d), "k": str(k),
                            "trial": str(t), "metric": "mse", "value": repr(scale * 100 / k)})  # fmt: skip
    return out


def _folder(tmp_path, sweep_points=(30,), seeds=2):
    units, rows = [], []
    study = {"strategies": ["random", "wavelet"], "metrics": ["mse"], "terrain_seeds": seeds}
    (tmp_path / "units").mkdir()
    rng = np.random.default_rng(0)
    for elev in sweep_points:
        for seed in range(seeds):
            i = len(units)
            units.append({
                "index": i, "key": f"k{i}",
                "sweep": {"render.light.elevation_deg": elev, "terrain.seed_index": seed},
                "config": {"terrain": {"seed_index": seed}, "study": study,
                           "figures": {"panel_density": 1 / 16}},
                "meta": {"shape": [16, 16], "spacing_m": 0.2},
                "scores": {"mse": {"random": 1.0, "wavelet": 2.0}},
            })  # fmt: skip
            rows += _rows(i)
            img = rng.random((16, 16))
            np.savez(tmp_path / "units" / f"k{i}.npz", image=img, wavelet_energy=img,
                     plan_rows=np.array([1, 5, 9]), plan_cols=np.array([2, 6, 10]),
                     reconstruction=img, depth=img)  # fmt: skip
    config = {"study": study, "sweep": {"render.light.elevation_deg": list(sweep_points)}}
    return {"dir": tmp_path, "units": units, "rows": rows, "config": config}


def _draw(res):
    drawn, captions = [], Captions()
    sf.sampling_figures(res, lambda fig, stem: drawn.append(stem), captions)
    return drawn, captions


def test_the_figures_of_one_point_with_two_terrain_seeds(tmp_path):
    drawn, captions = _draw(_folder(tmp_path))
    assert drawn == ["error_vs_density_mse", "panels_unit0", "panels_unit1", "samples_saved"]
    assert set(captions) == set(drawn)
    assert "k/N = 1/16" in captions["panels_unit0"]
    assert "elevation" in captions["panels_unit1"] and "terrain seed 1" in captions["panels_unit1"]


def test_score_against_a_one_axis_sweep_needs_scores_csv(tmp_path):
    res = _folder(tmp_path, sweep_points=(30, 60), seeds=1)
    drawn, _ = _draw(res)
    assert not any(s.startswith("score_vs_") for s in drawn)  # no scores.csv: no scores
    with open(tmp_path / "scores.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["point", "terrain_seed", "metric", "strategy", "score", "ci_low", "ci_high"])
        for point in ("elevation_deg=30", "elevation_deg=60"):
            w.writerow([point, "all", "mse", "random", 1.0, 1.0, 1.0])
            w.writerow([point, "all", "mse", "wavelet", 2.0, 1.8, 2.2])
    drawn, captions = _draw(res)
    assert "score_vs_elevation_deg_mse" in drawn and "score_vs_elevation_deg_mse" in captions
    assert drawn.count("samples_saved_point0") == 1 and "samples_saved_point1" in drawn


def test_a_corrupt_unit_file_is_named_before_any_figure(tmp_path):
    res = _folder(tmp_path)
    (tmp_path / "units" / "k1.npz").write_bytes(b"not a zip")
    with pytest.raises(ResultFolderError, match=r"k1\.npz: unreadable unit arrays"):
        _draw(res)


def test_unit_titles_and_cell_sizes():
    rec = {"sweep": {"render.light.elevation_deg": 30, "terrain.seed_index": 2},
           "config": {"terrain": {"seed_index": 2}}, "meta": {"spacing_m": 0.25}}  # fmt: skip
    assert sf._label(rec).endswith("; terrain seed 2")
    assert sf._label({"sweep": {}, "config": {"study": {"terrain_seeds": 3}}}) == "terrain seed 0"
    assert sf._label({"sweep": {}, "config": {}}) == ""
    assert sf._spacing(rec) == 0.25  # nadir orthographic: a pixel is a cell
    persp = {**rec, "config": {"render": {"camera": {"kind": "perspective"}}}}
    assert sf._spacing(persp) is None
    assert sf._spacing({"meta": {}}) is None
