"""The figures of a LIDAR result folder: two figures per metric (against scan time and against
samples), one panel per sweep point with its seeds pooled, or one panel whose curves run over a
swept sensor option; their captions say which."""

from __future__ import annotations

import matplotlib.pyplot as plt
import pytest

from simlunar.results.lidar_figures import MAX_PANELS, hazard_units, lidar_figures


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _rows(units, planners=("grid", "wavelet")):
    return [
        {"unit": str(u), "planner": p, "k": str(k), "trial": "0", "metric": m,
         "value": str((1 + u) / k), "seconds": str(k / 100)}
        for u in units for p in planners for k in (64, 256) for m in ("mse", "grad")
    ]  # fmt: skip


def _unit(i, elev, seed):
    return {"index": i, "sweep": {"render.light.elevation_deg": elev, "terrain.seed_index": seed},
            "config": {"terrain": {"seed_index": seed}}}  # fmt: skip


def _draw(res):
    figures, captions = [], {}
    lidar_figures(res, lambda fig, name: figures.append((name, fig)), captions)
    return figures, captions


def test_two_figures_per_metric_one_panel_per_point():
    units = [_unit(0, 30, 0), _unit(1, 30, 1), _unit(2, 60, 0), _unit(3, 60, 1)]
    res = {"config": {"study": {"metrics": ["mse", "grad"], "planners": ["wavelet", "grid"],
                                "trials": 2}, "sweep": {"render.light.elevation_deg": [30, 60]}},
           "units": units, "rows": _rows(range(4))}  # fmt: skip
    figures, captions = _draw(res)
    names = [n for n, _ in figures]
    assert names == ["lidar_error_vs_time_mse", "lidar_error_vs_samples_mse",
                     "lidar_error_vs_time_grad", "lidar_error_vs_samples_grad"]  # fmt: skip
    assert set(captions) == set(names)
    fig = figures[0][1]
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert len(panels) == 2  # two sweep points, their two terrain seeds pooled in each
    assert "One panel per sweep point." in captions["lidar_error_vs_time_mse"]
    assert "over the 2 terrain seeds" in captions["lidar_error_vs_time_mse"]
    assert "range samples measured" in captions["lidar_error_vs_samples_grad"]


def test_a_swept_sensor_option_is_one_panel_of_curves_over_its_values():
    units = [_unit(i, 30, 0) for i in range(3)]
    res = {"config": {"study": {"metrics": ["mse"], "sensor": "flash", "terrain_seeds": 1},
                      "sweep": {"study.options.flash.revisits": [0, 2, 4]}},
           "units": units, "rows": _rows(range(3))}  # fmt: skip
    figures, captions = _draw(res)
    assert len(figures) == 2
    cap = captions["lidar_error_vs_time_mse"]
    assert "Each point of a curve is one value of study.options.flash.revisits" in cap
    assert "Image-directed LIDAR (flash)" in cap and "One panel per sweep point" not in cap


def test_at_most_max_panels():
    units = [_unit(i, 10 * i, 0) for i in range(MAX_PANELS + 2)]
    res = {"config": {"study": {"metrics": ["mse"]}, "sweep": {"render.light.elevation_deg": []}},
           "units": units, "rows": _rows(range(MAX_PANELS + 2))}  # fmt: skip
    figures, _ = _draw(res)
    assert len([ax for ax in figures[0][1].axes if ax.get_title()]) == MAX_PANELS


def test_a_scan_figure_per_unit_from_its_cached_beams(tmp_path):
    import numpy as np

    from simlunar.results.store import UnitCache

    rng = np.random.default_rng(1)
    rc = rng.integers(0, 16, size=(20, 2)).astype(float)
    beams = np.c_[rc, np.arange(20) * 1e-3, 10.0 + rc[:, 0] / 16]
    arrays = {"image": rng.uniform(size=(16, 16)).astype(np.float32),
              "depth": 10.0 + np.tile(np.arange(16.0)[:, None] / 16, (1, 16)),
              "beams_random": beams, "beams_wavelet": beams[::-1].copy()}  # fmt: skip
    cache = UnitCache(tmp_path)
    cache.save("k0", {"rows": []}, arrays)
    cache.save("k1", {"rows": []}, {"image": arrays["image"], "depth": arrays["depth"]})
    study = {"metrics": ["mse"], "planners": ["wavelet", "random"], "sensor": "steered_beam",
             "densities": [1 / 16, 1 / 64]}  # fmt: skip
    units = [{**_unit(0, 30, 0), "key": "k0"}, {**_unit(1, 60, 0), "key": "k1"}]
    res = {"config": {"name": "exp", "study": study,
                      "sweep": {"render.light.elevation_deg": [30, 60]}},
           "units": units, "rows": _rows(range(2)), "dir": tmp_path}  # fmt: skip
    figures, captions = _draw(res)
    scans = [(n, f) for n, f in figures if n.startswith("lidar_scan")]
    # the second unit was cached without beams: no scan figure for it
    assert [n for n, _ in scans] == ["lidar_scan_unit0"]
    fig = scans[0][1]
    title = fig._suptitle.get_text()
    assert title.startswith("exp: steered beam scan, k/N = 1/16, trial 0")
    # planners in the study's order
    assert [ax.get_title() for ax in fig.axes[1:3]] == ["Wavelet: 20 beams", "Random: 20 beams"]
    cap = captions["lidar_scan_unit0"]
    assert "steered beam scan per planner (Wavelet; Random)" in cap
    assert "visited" in cap and "no range" in cap


def test_hazard_maps_take_the_sensors_in_turn_so_the_first_six_show_every_sensor():
    # 3 sensors x 3 lights x 2 terrain seeds, in sweep order (sensor, light, seed): the first
    # six of seed 0 in index order would be the flash and the steered beam only
    records = [
        {"index": i, "sweep": {"study.sensor": s, "render.light.elevation_deg": e},
         "config": {"terrain": {"seed_index": seed}}}
        for i, (s, e, seed) in enumerate(
            (s, e, seed) for s in ("flash", "steered_beam", "micromirror_flash")
            for e in (3, 8, 45) for seed in (0, 1)
        )
    ]  # fmt: skip
    order = hazard_units(records)
    assert len(order) == 9  # seed 0 only
    first = order[:MAX_PANELS]
    assert [r["sweep"]["study.sensor"] for r in first[:3]] == [
        "flash", "steered_beam", "micromirror_flash"]  # fmt: skip
    assert [r["index"] for r in first] == [0, 6, 12, 2, 8, 14]
    # one sensor (no sensor axis): the units in their own order
    one = [{**r, "sweep": {"render.light.elevation_deg": 3}} for r in records[:4]]
    assert [r["index"] for r in hazard_units(one)] == [0, 2]
