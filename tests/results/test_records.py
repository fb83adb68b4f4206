"""Work units and their records: the dict form the cache stores (scans only when present), and
the short label of a sweep point."""

from __future__ import annotations

import numpy as np

from simlunar.results.records import UnitRecord, WorkUnit, unit_label


def test_the_dict_form_leaves_out_absent_scans():
    r = UnitRecord(rows=[{"metric": "mse", "value": 1.0}], scores={"mse": {"random": 1.0}},
                   arrays={"image": np.zeros((2, 2))}, timings={"render": 0.5})  # fmt: skip
    d = r.to_dict()
    assert list(d) == ["rows", "scores", "arrays", "timings", "meta"]
    assert d["meta"] == {} and d["rows"] is r.rows
    with_scans = UnitRecord([], {}, {}, {}, scans={"depth": np.ones(1)}).to_dict()
    assert list(with_scans) == ["rows", "scores", "arrays", "timings", "meta", "scans"]


def _unit(sweep, *, seed=None, name="exp"):
    return WorkUnit(index=3, key="abc", sweep=sweep, config={"name": name}, terrain_seed=seed)


def test_labels_of_sweep_points():
    assert unit_label(_unit({})) == "exp"
    assert unit_label(WorkUnit(2, "k", {}, {})) == "unit 2"
    assert unit_label(_unit({}, seed=4)) == "terrain_seed=4"
    assert unit_label(_unit({"render.light.elevation_deg": 30.0})) == "elevation_deg=30.0"
    assert unit_label(_unit({"a.b": 2, "c.flag": True}, seed=1)) == "b=2, flag=true, terrain_seed=1"
    assert unit_label(_unit({"render.sensor": None})) == "sensor=default"
    assert unit_label(_unit({"render.bsdf": {"kind": "lambert"}})) == "bsdf=lambert"
    mast = {"kind": "rover_mast", "depression_deg": 30, "height_m": 1.5}
    assert unit_label(_unit({"render.camera": mast})) == (
        "camera=rover_mast(depression_deg=30, height_m=1.5)"
    )
    assert unit_label(_unit({"terrain.overrides": {"fractal": {"rms_m": 0.1}}})) == (
        'overrides={"fractal": {"rms_m": 0.1}}'
    )
    assert unit_label(_unit({"study.densities": [0.5, 0.25]})) == "densities=[0.5, 0.25]"
