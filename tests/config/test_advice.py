"""Warnings for valid but probably unintended settings: a sun below 1 deg."""

from __future__ import annotations

from simlunar.config.advice import LOW_SUN_DEG, config_warnings
from simlunar.config.loading import validate_data


def _cfg(light=None, sweep=None):
    d = {
        "name": "t",
        "terrain": {"preset": "aerial_1", "scale": 0.125},
        "study": {"strategies": ["random"], "densities": ["1/2"], "trials": 1},
    }
    if light is not None:
        d["render"] = {"light": light}
    if sweep is not None:
        d["sweep"] = sweep
    return validate_data(d)


def test_a_sun_below_one_degree_is_warned_about_not_refused():
    (line,) = config_warnings(_cfg({"kind": "sun", "elevation_deg": 0.5}))
    assert line.startswith("warning: render.light.elevation_deg: the sun at 0.5 deg is below 1")
    assert config_warnings(_cfg({"kind": "sun", "elevation_deg": LOW_SUN_DEG})) == []
    assert config_warnings(_cfg({"kind": "sun", "elevation_deg": 30})) == []
    assert config_warnings(_cfg({"kind": "camera"})) == []
    assert config_warnings(_cfg()) == []  # the default sun, 30 deg


def test_each_low_sweep_value_is_named():
    lines = config_warnings(_cfg(sweep={"render.light.elevation_deg": [0.2, 15, 0.9, 1.0]}))
    assert [ln.split(":")[1].strip() for ln in lines] == [
        "sweep.render.light.elevation_deg[0]",
        "sweep.render.light.elevation_deg[2]",
    ]
    # a sweep over whole lights: the sun entries are checked, the camera light is not
    lines = config_warnings(
        _cfg(sweep={"render.light": [{"kind": "camera"}, {"kind": "sun", "elevation_deg": 0.3}]})
    )
    assert len(lines) == 1 and "sweep.render.light[1]" in lines[0] and "0.3 deg" in lines[0]
