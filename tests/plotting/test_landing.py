"""Landing figures: the bars are the table's means, the hazard panel colours what it says."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from simlunar.plotting.landing import hazard_map_panel, landing_cost, landing_recall


def _rows():
    rows = []
    for unit, sensor, light, recall in ((0, "flash", 5, 0.2), (1, "flash", 5, 0.6),
                                        (2, "steered_beam", 45, 1.0)):  # fmt: skip
        for metric, value in (("hazard_recall_rock_15cm", recall), ("false_safe_site", 1.0)):
            rows.append({"unit": unit, "study.sensor": sensor, "render.light.elevation_deg": light,
                         "planner": "none", "reconstruction": "linear", "metric": metric,
                         "value": value, "seconds": 0.5})  # fmt: skip
    return rows


def test_recall_bars_are_the_means_over_seeds_one_panel_per_light():
    fig = landing_recall(_rows(), sensor_key="study.sensor",
                         light_key="render.light.elevation_deg")  # fmt: skip
    try:
        axes = [ax for ax in fig.axes if ax.patches]
        assert [ax.get_title() for ax in axes] == ["sun 5 deg", "sun 45 deg"]
        heights = [p.get_height() for p in axes[0].patches]
        # groups (flash, steered_beam) x metrics (rock 15 cm recall, false-safe site)
        assert heights[0] == pytest.approx(0.4)  # flash at 5 deg: mean of 0.2 and 0.6
        assert heights[2] == pytest.approx(1.0)  # its false-safe site
        assert np.isnan(heights[1])  # no steered beam at 5 deg
        labels = [t.get_text() for t in fig.legends[0].get_texts()]
        assert labels == ["rock 15cm recall", "false-safe site"]
    finally:
        plt.close(fig)


def test_precision_sits_on_its_recall_bar_and_a_group_that_called_no_site_safe_says_so():
    # the flash: recall 0.8 at precision 0.9, a site called safe (false-safe 0.5); the
    # micromirror: recall 0.9 made of false alarms (precision 0.05), no site ever called safe
    rows = []
    for unit in (0, 1):
        for sensor, rec, prec, called, fs in (
            ("flash", 0.8, 0.9, 1.0, unit * 1.0),
            ("micromirror_flash", 0.9, 0.05, 0.0, 0.0),
        ):
            for metric, value in (
                ("hazard_recall_rock_15cm", rec),
                ("hazard_precision_rock_15cm", prec),
                ("false_safe_site", fs),
                ("safe_site_called", called),
            ):
                rows.append({"unit": f"{sensor}{unit}", "study.sensor": sensor,
                             "planner": "none", "reconstruction": "linear", "metric": metric,
                             "value": value, "seconds": 0.5})  # fmt: skip
    fig = landing_recall(rows, sensor_key="study.sensor", light_key=None)
    try:
        ax = fig.axes[0]
        diamonds = [ln for ln in ax.lines if ln.get_marker() == "D"]
        assert len(diamonds) == 1
        assert diamonds[0].get_ydata().tolist() == pytest.approx([0.9, 0.05])
        heights = [p.get_height() for p in ax.patches]
        # bars: recall (flash, micromirror), then false-safe (flash, micromirror)
        assert heights[:3] == pytest.approx([0.8, 0.9, 0.5])
        assert np.isnan(heights[3])  # no site called safe: no false-safe bar ...
        assert [t.get_text() for t in ax.texts] == ["no safe site"]  # ... but words
        labels = [t.get_text() for t in fig.legends[0].get_texts()]
        assert labels == ["rock 15cm recall", "false-safe site", "precision of that hazard"]
    finally:
        plt.close(fig)


def test_cost_curves_put_each_sensor_s_planners_at_their_time_and_energy():
    # the flash (one point: 0.13 s, 0.12 J); a steered beam's lloyd plan at 1 s / 0.04 J and
    # the same strategy fitted to a 0.1 s budget (0.004 J); its wavelet plan, whose energy was
    # never priced (NaN)
    rows = []
    for unit in (0, 1):
        for sensor, planner, s, e, recall in (
            ("flash", "none", 0.13, 0.12, 0.6 + 0.1 * unit),
            ("steered_beam", "lloyd", 1.0, 0.04, 0.3),
            ("steered_beam", "lloyd_fast", 0.1, 0.004, 0.1),
            ("steered_beam", "wavelet", 2.0, float("nan"), 0.5),
        ):
            for m, v in (("hazard_recall_rock_30cm", 0.9), ("hazard_recall_rock_15cm", recall)):
                rows.append({"unit": unit, "study.sensor": sensor, "planner": planner,
                             "reconstruction": "linear", "metric": m, "value": v, "seconds": s,
                             "energy_j": e})  # fmt: skip
    fig = landing_cost(rows, sensor_key="study.sensor", light_key=None,
                       strategies={"lloyd_fast": "lloyd"})  # fmt: skip
    try:
        t_ax, e_ax = fig.axes[:2]
        assert t_ax.get_xscale() == e_ax.get_xscale() == "log"
        assert t_ax.get_ylabel() == "rock 15cm recall"  # the smallest rock by default
        assert (t_ax.get_xlabel(), e_ax.get_xlabel()) == ("scan time (s)", "laser energy (J)")
        lines = {c.get_label(): c.lines[0] for c in t_ax.containers}
        assert set(lines) == {"flash", "steered beam, lloyd", "steered beam, wavelet"}
        x, y = lines["flash"].get_data()
        assert list(x) == [0.13] and list(y) == [pytest.approx(0.65)]
        # one strategy's plans joined in order of time: the 0.1 s fit, then the 1 s plan
        x, y = lines["steered beam, lloyd"].get_data()
        assert list(x) == [0.1, 1.0] and list(y) == [0.1, 0.3]
        assert (
            lines["steered beam, lloyd"].get_marker() != lines["steered beam, wavelet"].get_marker()
        )
        # on the energy axis the unpriced plan is left out
        e_lines = {c.get_label(): c.lines[0] for c in e_ax.containers}
        assert set(e_lines) == {"flash", "steered beam, lloyd"}
        assert list(e_lines["steered beam, lloyd"].get_data()[0]) == [0.004, 0.04]
    finally:
        plt.close(fig)
    # without a rock recall there is nothing to draw
    no_rocks = [{**r, "metric": "false_safe_site"} for r in rows]
    assert landing_cost(no_rocks, sensor_key="study.sensor", light_key=None) is None


def test_cost_curves_carry_each_plan_s_precision_dashed():
    # two plans of one strategy at 1 s and 2 s: recall 0.3 / 0.8 at precision 0.9 / 0.1 (the
    # second recall bought with false alarms); the flash has no precision row: no dashed line
    rows = []
    for sensor, planner, s, recall, prec in (("micromirror_flash", "lloyd", 1.0, 0.3, 0.9),
                                             ("micromirror_flash", "lloyd_big", 2.0, 0.8, 0.1),
                                             ("flash", "none", 0.13, 0.5, None)):  # fmt: skip
        for m, v in (("hazard_recall_rock_15cm", recall), ("hazard_precision_rock_15cm", prec)):
            if v is not None:
                rows.append({"unit": 0, "study.sensor": sensor, "planner": planner,
                             "reconstruction": "linear", "metric": m, "value": v, "seconds": s,
                             "energy_j": 0.01 * s})  # fmt: skip
    fig = landing_cost(rows, sensor_key="study.sensor", light_key=None,
                       strategies={"lloyd_big": "lloyd"})  # fmt: skip
    try:
        t_ax = fig.axes[0]
        dashed = [ln for ln in t_ax.lines if ln.get_gid() == "precision"]
        assert len(dashed) == 1 and dashed[0].get_linestyle() == "--"
        assert list(dashed[0].get_xdata()) == [1.0, 2.0]
        assert list(dashed[0].get_ydata()) == pytest.approx([0.9, 0.1])
        labels = [t.get_text() for t in fig.legends[0].get_texts()]
        assert labels[-1] == "rock 15cm precision"
        assert t_ax.get_ylabel() == "rock 15cm recall / precision"
        assert "dashed, open: the same plans' precision" in fig._suptitle.get_text()
    finally:
        plt.close(fig)


def test_hazard_panel_colours_found_missed_and_false_alarms():
    truth = np.zeros((4, 4), bool)
    truth[0, 0] = truth[1, 1] = True
    found = np.zeros_like(truth)
    found[0, 0] = found[3, 3] = True
    fig = hazard_map_panel(np.zeros((4, 4)), truth, {"flash, linear": found})
    try:
        rgb = fig.axes[2].images[0].get_array()
        assert tuple(rgb[0, 0]) == (0.0, 0.0, 0.0)  # found
        assert tuple(rgb[1, 1]) == pytest.approx((0.85, 0.1, 0.1))  # missed
        assert tuple(rgb[3, 3]) == pytest.approx((0.2, 0.4, 0.9))  # false alarm
        assert tuple(rgb[2, 2]) == (1.0, 1.0, 1.0)
        assert fig.axes[2].get_title() == "flash, linear"
    finally:
        plt.close(fig)


def test_a_hazard_panel_of_many_reconstructions_wraps_into_even_rows():
    # guide + truth + 12 reconstructions = 14 panels: 2 rows of 7 (was one row of 14); 5
    # panels stay in one row
    truth = np.zeros((4, 4), bool)
    found = {f"plan {i}, linear": truth for i in range(12)}
    fig = hazard_map_panel(np.zeros((4, 4)), truth, found)
    try:
        assert len(fig.axes) == 14
        rows = sorted({round(ax.get_position().y0, 3) for ax in fig.axes})
        cols = sorted({round(ax.get_position().x0, 3) for ax in fig.axes})
        assert len(rows) == 2 and len(cols) == 7
        assert fig.axes[2].get_title() == "plan 0, linear"
    finally:
        plt.close(fig)
    fig = hazard_map_panel(np.zeros((4, 4)), truth, dict(list(found.items())[:3]))
    try:
        assert len({round(ax.get_position().y0, 3) for ax in fig.axes}) == 1
    finally:
        plt.close(fig)
