"""The figures of a LIDAR result folder: two figures per metric (against scan time and against
samples), one panel per sweep point with its seeds pooled, or one panel whose curves run over a
swept sensor option; their captions say which."""

from __future__ import annotations

import matplotlib.pyplot as plt
import pytest

from simlunar.results.lidar_figures import MAX_PANELS, lidar_figures


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
