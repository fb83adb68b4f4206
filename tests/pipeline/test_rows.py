"""The rows of ``results.csv`` (simlunar/pipeline/rows.py): their order and columns."""

from __future__ import annotations

from simlunar.pipeline.rows import collect_rows
from simlunar.results.records import WorkUnit


def test_results_columns_do_not_depend_on_the_order_of_a_records_keys():
    """A resumed run mixes cached records (JSON, keys sorted) and fresh ones (the study's
    order): the CSV columns must be the same either way (a resumed LIDAR sweep wrote them in
    another order)."""
    fresh = {
        "planner": "random",
        "k": 4,
        "seconds": 1.5,
        "frames": 3,
        "metric": "mse",
        "value": 1.0,
    }
    cached = dict(sorted(fresh.items()))
    units = [WorkUnit(0, "a", {"x": 1}, {}), WorkUnit(1, "b", {"x": 2}, {})]
    cols = []
    for first, second in ((fresh, cached), (cached, fresh), (cached, cached)):
        _, c = collect_rows(units, {"a": {"rows": [first]}, "b": {"rows": [second]}})
        cols.append(c)
    assert cols[0] == cols[1] == cols[2]
    # a row without a reconstruction is linear's (rows written before reconstructions existed)
    assert cols[0] == [
        "unit",
        "x",
        "planner",
        "reconstruction",
        "k",
        "metric",
        "frames",
        "seconds",
        "value",
    ]
