"""simlunar run --dry-run: the units, a cost estimate from the documented model, nothing
written."""

from __future__ import annotations

import pytest
from fake_unit import fake_unit

from simlunar.config.loading import validate_data
from simlunar.errors import ConfigError
from simlunar.pipeline import estimate as E
from simlunar.pipeline.runner import run_experiment


def _cfg(**study):
    return validate_data(
        {
            "name": "est",
            "terrain": {"preset": "aerial_1", "scale": 0.125},  # 125 x 200 cells
            "render": {"spp": 4},
            "study": {
                "strategies": ["random", "grid", "lloyd_uniform"],
                "densities": ["1/2", "1/8"],
                "trials": 3,
                **study,
            },
            "sweep": {"render.light.elevation_deg": [10, 40]},
        }
    )


def test_estimate_is_the_documented_model(tmp_path):
    est = E.estimate_run(_cfg(), tmp_path / "o", workers=1, figures=False)
    assert est.units == ["elevation_deg=10", "elevation_deg=40"] and est.cached == 0
    cells = pixels = 125 * 200  # the nadir view renders one pixel per cell
    tasks = (1 + 1 + E.HEAVY_FACTOR) * 2 * 3
    unit = (
        E.TERRAIN_S
        + E.TERRAIN_S_PER_CELL * cells
        + E.RENDER_S
        + E.RENDER_S_PER_SAMPLE * pixels * 4
        + tasks * (E.TASK_S + E.TASK_S_PER_CELL * cells)
    )
    assert est.seconds == pytest.approx(E.START_S + 2 * unit)
    # two workers: the units in parallel; figures: a second render per unit
    two = E.estimate_run(_cfg(), tmp_path / "o", workers=2, figures=False)
    assert two.seconds == pytest.approx(E.START_S + unit)
    figs = E.estimate_run(_cfg(), tmp_path / "o", workers=1, figures=True)
    extra = 2 * (E.RENDER_S + E.RENDER_S_PER_SAMPLE * pixels * 4)
    assert figs.seconds == pytest.approx(est.seconds + extra)
    assert est.peak_bytes == pytest.approx(E.BASE_BYTES + E.BYTES_PER_CELL * cells)
    assert not (tmp_path / "o").exists()


def test_finished_units_cost_nothing(tmp_path):
    cfg = _cfg()
    out = tmp_path / "o"
    run_experiment(cfg, out, compute=fake_unit, progress=False, figures=False)
    est = E.estimate_run(cfg, out, figures=False)
    assert est.cached == 2 and est.seconds == pytest.approx(E.START_S)
    text = "\n".join(est.lines(out))
    assert "work units: 2 (2 already in the folder, 0 to compute)" in text
    assert "estimated time: 4 s" in text and "nothing written" in text


def test_dry_run_stops_where_the_run_would(tmp_path):
    # the preflight checks run: a density giving too few samples on the 125 x 200 image
    with pytest.raises(ConfigError, match=r"study.densities\[1\]: density .* gives 0 samples"):
        E.estimate_run(_cfg(densities=["1/2", 1e-6]), tmp_path, figures=False)


def test_other_study_kinds_have_no_time_model(tmp_path):
    est = E.RunEstimate(units=["a"], cached=0, seconds=None, peak_bytes=1e9)
    assert "no time model for this study kind" in "\n".join(est.lines(tmp_path))
