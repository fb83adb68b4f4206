"""A derived frame (the ratio ``sun/sun2`` a reconstruction reads) costs no exposure: the
``exposures`` column counts the camera exposures behind the frames a row names."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.pipeline.rows import collect_rows
from simlunar.reconstruction import RECONSTRUCTIONS, Guide
from simlunar.results.records import WorkUnit
from simlunar.study.protocol import exposure_count, guide_cost


@pytest.mark.parametrize(
    ("frames", "want"),
    [
        (("sun", "sun2", "sun/sun2"), 2),  # was 3 for 2 frames
        ("sun+sun2+sun/sun2", 2),
        ("sun+camera+sun/camera", 2),
        (("sun", "camera", "sun_60"), 3),
        (("sun/sun2",), 2),  # the ratio alone: both exposures were taken
        ("sun", 1),
        ("", 0),
        ((), 0),
    ],
)
def test_exposure_count(frames, want):
    assert exposure_count(frames) == want


def test_guide_cost_of_a_ratio_frame():
    guided = next(n for n, e in RECONSTRUCTIONS.items() if e.meta.get("guided"))
    g = Guide(np.ones((3, 3)), frames=("sun", "sun2"))
    assert guide_cost(guided, g, {"frames": "sun+sun2+sun/sun2"}) == (
        ("sun", "sun2", "sun/sun2"),
        2,
    )


def test_rows_cached_with_the_old_count_are_counted_again():
    # a record cached when the ratio counted as an exposure: the rows say 2 (from the frames)
    row = {"strategy": "random", "reconstruction": "shading", "guide_frames": "sun+sun2+sun/sun2",
           "exposures": 3, "density": 0.0625, "k": 4, "trial": 0, "metric": "mse", "value": 1.0}  # fmt: skip
    linear = {**row, "reconstruction": "linear", "guide_frames": "", "exposures": 0}
    unit = WorkUnit(0, "k0", {}, {"study": {"strategies": ["random"], "metrics": ["mse"]}})
    rows, _ = collect_rows([unit], {"k0": {"rows": [linear, row]}})
    assert [(r["reconstruction"], r["exposures"]) for r in rows] == [("linear", 0), ("shading", 2)]
