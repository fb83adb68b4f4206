"""Landing tables: every sensor, light and hazard size named; intervals over terrain seeds."""

import pytest

from simlunar.plotting.landing_tables import landing_columns, landing_summary, landing_tables


def _rows():
    rows = []
    # two terrain seeds (units 0, 1) of the flash at 5 deg, and one of the beam at 45 deg
    for unit, sensor, light, recall in ((0, "flash", 5, 0.2), (1, "flash", 5, 0.6),
                                        (2, "steered_beam", 45, 1.0)):  # fmt: skip
        for metric, value in (("hazard_recall_rock_15cm", recall), ("false_safe_site", 1.0),
                              ("rmse", 9.0)):  # fmt: skip
            rows.append({"unit": unit, "study.sensor": sensor, "render.light.elevation_deg": light,
                         "planner": "none", "reconstruction": "linear", "metric": metric,
                         "value": value, "seconds": 0.5, "energy_j": 0.1 * (unit + 1)})  # fmt: skip
    return rows


def test_columns_are_the_landing_metrics_only():
    assert landing_columns(_rows()) == ["hazard_recall_rock_15cm", "false_safe_site"]


def test_summary_means_over_units_with_an_interval():
    keys = ["study.sensor", "render.light.elevation_deg"]
    s = landing_summary(_rows(), keys=keys)
    mean, lo, hi = s[("flash", "5", "linear", "none")]["hazard_recall_rock_15cm"]
    assert mean == pytest.approx(0.4)
    assert 0.2 <= lo <= mean <= hi <= 0.6 and hi > lo
    assert s[("steered_beam", "45", "linear", "none")]["hazard_recall_rock_15cm"] == (1.0, 1.0, 1.0)
    # the laser energy: the mean of the group's rows (0.1 and 0.2 J), NaN where never priced
    assert s[("flash", "5", "linear", "none")]["energy_j"] == pytest.approx(0.15)
    old = [{k: v for k, v in r.items() if k != "energy_j"} for r in _rows()]
    import math

    assert math.isnan(landing_summary(old, keys=keys)[("flash", "5", "linear", "none")]["energy_j"])


def test_table_names_sensor_light_and_size():
    md, tex = landing_tables(
        _rows(), keys=["study.sensor", "render.light.elevation_deg"], title="t"
    )
    assert "| sensor | elevation_deg | reconstruction | planner |" in md
    assert "rock 15cm recall" in md and "false-safe site" in md and "rmse" not in md.lower()
    assert "| flash | 5 | linear | none | 0.5 | 0.15 |" in md and "| steered_beam | 45 |" in md
    assert "| scan time (s) | laser energy (J) |" in md
    assert "0.4 [" in md
    assert "steered\\_beam" in tex


def test_no_landing_metric_no_table():
    rows = [r for r in _rows() if r["metric"] == "rmse"]
    assert landing_tables(rows, keys=[], title="t") == ("", "")


@pytest.mark.parametrize(
    "diffs, p",
    [([1, 2, 3, 4, 5, 6, 7, 8], 2 / 256),  # every sign agrees: 2 of 2^8 patterns as extreme
     ([1, 2], 0.5), ([3, -1], 1.0), ([0, 0, 0], 1.0), ([], 1.0)],
)  # fmt: skip
def test_sign_flip_p_by_hand(diffs, p):
    from simlunar.plotting.landing_tables import paired_sign_flip_p

    assert paired_sign_flip_p(diffs) == pytest.approx(p)


def test_paired_table_differences_on_the_same_seeds():
    from simlunar.plotting.landing_tables import paired_table

    rows = []
    for seed in (0, 1, 2):
        for sensor, recall in (("flash", 0.9), ("steered_beam", 0.5 + 0.1 * seed)):
            rows.append({"study.sensor": sensor, "terrain_seed": seed, "planner": "none",
                         "reconstruction": "linear", "metric": "hazard_recall_rock_15cm",
                         "value": recall, "seconds": 1.0})  # fmt: skip
    md = paired_table(rows, sensor_key="study.sensor", light_key=None, title="t")
    # differences -0.4, -0.3, -0.2: mean -0.3, all one sign: p = 2 / 8
    assert "| steered_beam | none | -0.3 (p = 0.25) |" in md
    assert "flash | none | -" not in md  # the reference is not compared with itself
    one_seed = [r for r in rows if r["terrain_seed"] == 0]
    assert paired_table(one_seed, sensor_key="study.sensor", light_key=None) == ""
