"""Scanner-study setup (simlunar.study.scanner_setup)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.planner import strategy_weights
from simlunar.study import scanner
from simlunar.study.scanner_setup import _scan_planner, aim_rig_at_terrain, guided_weights


def test_guided_weights_take_the_feature_options_and_return_the_rest():
    image = np.random.default_rng(0).uniform(0.1, 1.0, (16, 20))
    w, rest = guided_weights("gradient", image, {"feature_opts": None, "min_dist": 2})
    np.testing.assert_array_equal(w, strategy_weights("gradient", image))
    assert rest == {"min_dist": 2}


class _Opts:
    def __init__(self):
        self.planner_opts = {"low_contrast": {"x": 1}}


@pytest.mark.parametrize(
    ("mode", "message"),
    [
        ("gray_code", "ranks the pixels of a coded scan: use it with the ambiguity_enhancement"),
        ("ambiguity_enhancement", r"takes no options, got \['x'\]"),
    ],
)
def test_scan_planners_refuse_other_modes_and_options(mode, message):
    with pytest.raises(ValueError, match=message):
        _scan_planner("low_contrast", _Opts(), mode, guide=None, sensor=None)


def test_unknown_rig_preset_is_refused():
    with pytest.raises(ValueError, match="unknown rig preset 'mars'; valid: "):
        aim_rig_at_terrain(None, preset="mars")


def test_scanner_re_exports_the_setup():
    assert scanner.aim_rig_at_terrain is aim_rig_at_terrain
    assert scanner.guided_weights is guided_weights
