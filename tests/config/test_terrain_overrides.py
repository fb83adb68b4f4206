"""``terrain.overrides``: typed preset sections, key-path errors, sweeps, cache keys."""

from __future__ import annotations

import csv

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.config.loading import check_key_path, load_experiment, validate_data
from simlunar.config.translate import build_terrain
from simlunar.errors import ConfigError
from simlunar.pipeline.runner import expand, unit_key

BASE = {
    "name": "ovr",
    "seed": 1,
    "terrain": {"preset": "aerial_1", "scale": 0.0625},
    "render": {"spp": 4},
    "study": {
        "strategies": ["random", "grid"],
        "densities": ["1/4", "1/16"],
        "trials": 2,
        "metrics": ["mse"],
    },
}


def with_terrain(**kw) -> dict:
    return {**BASE, "terrain": {**BASE["terrain"], **kw}}


def write(tmp_path, data) -> str:
    p = tmp_path / "exp.yaml"
    p.write_text(yaml.safe_dump(data))
    return str(p)


def test_overrides_change_the_terrain():
    plain = validate_data(BASE)
    smooth = validate_data(with_terrain(overrides={"fractal": {"rms_m": 0.0}}))
    assert smooth.terrain.overrides.as_mapping() == {"fractal": {"rms_m": 0.0}}
    a = build_terrain(plain.terrain, rng=np.random.default_rng(0))
    b = build_terrain(smooth.terrain, rng=np.random.default_rng(0))
    assert a.shape == b.shape == (62, 100)
    # the preset's fBm has rms 0.25 m; without it only craters (and rocks) remain, so the
    # difference is the fBm field itself (see tests/terrain/test_overrides.py)
    assert (a.heights - b.heights).std() == pytest.approx(0.25, rel=1e-3)
    np.testing.assert_array_equal(a.albedo, b.albedo)


ERRORS = [
    (
        {"fractal": {"rms_mm": 2.0}},
        "terrain.overrides.fractal.rms_mm: unknown key (valid keys: hurst, rms_m, periodic, "
        "rolloff_m) (did you mean 'rms_m'?)",
    ),
    (
        {"fractal": {"rms_m": -0.05}},
        "terrain.overrides.fractal.rms_m: Input should be greater than or equal to 0",
    ),
    (
        {"rocks": {"albedo_contrast": "bright"}},
        "terrain.overrides.rocks.albedo_contrast: Input should be a valid number, unable to "
        "parse string as a number",
    ),
    (
        {"fractl": {"rms_m": 0.1}},
        "terrain.overrides.fractl: unknown key (valid keys: grid, fractal, bed, craters, rocks, "
        "albedo) (did you mean 'fractal'?)",
    ),
    (
        {"rocks": {"d_max_m": 0.1}},  # below the preset's d_min_m = 0.4: a cross-field error
        "terrain.overrides.rocks.d_max_m: the diameter range is empty (0.1 <= d_min_m 0.4)",
    ),
]


@pytest.mark.parametrize(("overrides", "message"), ERRORS, ids=[m[:40] for _, m in ERRORS])
def test_bad_overrides_give_one_line_naming_the_path(overrides, message):
    with pytest.raises(ConfigError) as info:
        validate_data(with_terrain(overrides=overrides))
    assert str(info.value) == message


def test_overrides_need_a_preset():
    data = {**BASE, "terrain": {"file": "x.npy", "spacing_m": 0.2, "overrides": {"bed": {}}}}
    with pytest.raises(ConfigError, match=r"^terrain.overrides: overrides apply to a preset only"):
        validate_data(data)


@pytest.mark.parametrize(
    ("overrides", "expected"),
    [
        ({"fractal": {"rms_mm": 2.0}}, "terrain.overrides.fractal.rms_mm: unknown key"),
        ({"fractal": {"rms_m": -1}}, "terrain.overrides.fractal.rms_m: Input should be greater"),
    ],
)
def test_cli_bad_override_is_one_line_exit_2_nothing_written(overrides, expected, tmp_path):
    path = write(tmp_path, with_terrain(overrides=overrides))
    out = tmp_path / "results"
    r = CliRunner().invoke(app, ["run", path, "--out", str(out), "--no-progress"])
    assert r.exit_code == 2, r.output
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith(f"error: {path}: {expected}"), r.output
    assert not out.exists()


def test_sweep_keys_under_overrides_are_checked_against_the_terrain_params():
    check_key_path("terrain.overrides.fractal.rms_m", BASE)
    check_key_path("terrain.overrides.rocks", BASE)  # a whole section as the sweep value
    with pytest.raises(ConfigError, match=r"^sweep.terrain.overrides.fractal.rms_mm: no such"):
        check_key_path("terrain.overrides.fractal.rms_mm", BASE)
    with pytest.raises(ConfigError, match=r"^sweep.terrain.overrides.fractl.rms_m: no such"):
        check_key_path("terrain.overrides.fractl.rms_m", BASE)
    with pytest.raises(ConfigError, match=r"valid keys under terrain.overrides.fractal: hurst"):
        check_key_path("terrain.overrides.fractal.rms_m.x", BASE)


def test_sweep_over_an_override_validates_every_point():
    cfg = validate_data({**BASE, "sweep": {"terrain.overrides.fractal.rms_m": [0.0, 0.1]}})
    units = expand(cfg)
    assert [u.config["terrain"]["overrides"] for u in units] == [
        {"fractal": {"rms_m": 0.0}},
        {"fractal": {"rms_m": 0.1}},
    ]
    bad = {**BASE, "sweep": {"terrain.overrides.fractal.rms_m": [0.0, -0.1]}}
    with pytest.raises(ConfigError) as info:
        validate_data(bad)
    assert str(info.value) == (
        "sweep.terrain.overrides.fractal.rms_m[1]: terrain.overrides.fractal.rms_m: "
        "Input should be greater than or equal to 0"
    )


def test_set_reaches_override_keys(tmp_path):
    path = write(tmp_path, BASE)
    cfg = load_experiment(path, {"terrain.overrides.fractal.rms_m": 0.1})
    assert cfg.terrain.overrides.as_mapping() == {"fractal": {"rms_m": 0.1}}
    with pytest.raises(ConfigError, match=r"--set terrain\.overrides\.bed\.amp: no such"):
        load_experiment(path, {"terrain.overrides.bed.amp": 0.1})


def test_cache_key_includes_overrides_and_empty_overrides_keep_old_keys():
    (plain,) = expand(validate_data(BASE))
    (same,) = expand(validate_data(with_terrain(overrides={})))
    (rough,) = expand(validate_data(with_terrain(overrides={"fractal": {"rms_m": 0.1}})))
    (rough2,) = expand(validate_data(with_terrain(overrides={"fractal": {"rms_m": 0.2}})))
    assert len({plain.key, rough.key, rough2.key}) == 3
    assert same.key == plain.key
    # no overrides: the key is the one computed before the overrides field existed
    legacy = {k: v for k, v in plain.config.items()}
    legacy["terrain"] = {k: v for k, v in plain.config["terrain"].items() if k != "overrides"}
    assert unit_key(legacy) == plain.key


@pytest.mark.render
def test_sweep_over_an_override_runs(tmp_path):
    data = {**BASE, "sweep": {"terrain.overrides.fractal.rms_m": [0.0, 0.25]}}
    data["figures"] = {"enabled": False}
    path = write(tmp_path, data)
    out = tmp_path / "res"
    r = CliRunner().invoke(app, ["run", path, "--out", str(out), "--no-progress"])
    assert r.exit_code == 0, r.output
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 * 2 * 2 * 2  # points x strategies x densities x trials
    axis = "terrain.overrides.fractal.rms_m"
    by_point = {
        p: {
            (x["strategy"], x["density"], x["trial"]): float(x["value"])
            for x in rows
            if x[axis] == p
        }
        for p in ("0.0", "0.25")
    }
    # same craters and sampling trials at both points: the 0.25 m fBm (cell-to-cell relief)
    # adds interpolation error at every strategy, density and trial
    assert by_point["0.0"].keys() == by_point["0.25"].keys()
    assert all(by_point["0.25"][k] > v for k, v in by_point["0.0"].items())
