"""The rules a LIDAR study's options must meet together, checked on the schema's values
(one line naming the offending key, before anything runs)."""

from __future__ import annotations

import pytest

from simlunar.config.lidar_checks import LIDAR_PLANNER_RULES, check_lidar_study
from simlunar.config.studies import LidarStudyCfg


def study(**kw) -> LidarStudyCfg:
    return LidarStudyCfg.model_validate({"kind": "lidar", **kw})


def test_the_default_study_passes_and_every_rule_names_a_strategy():
    check_lidar_study(study())
    assert set(LIDAR_PLANNER_RULES) == {"oracle_greedy", "oracle_hessian", "sequential"}


@pytest.mark.parametrize(
    "kw, match",
    [
        (
            {"planners": ["bound"], "planner_opts": {"bound": {"strategy": "oracle_hessian"}}},
            r"study.planners\[0\]: the label 'bound' .* must start with 'oracle'",
        ),
        ({"sensor": "flash", "planners": ["sequential"]}, "measures its receiver pixels"),
        (
            {"planner_opts": {"random": {"fit": {"kind": "receiver"}}}},
            "study.planner_opts.random.fit: a receiver fit is for the micromirror_flash",
        ),
        ({"options": {"margin_m": 5}}, "study.options.margin_m: 5 m leaves no range"),
        ({"options": {"bin_range_m": 1e-6}}, "study.options.bin_range_m: .* time bins"),
    ],
)
def test_a_bad_combination_is_one_line_naming_its_key(kw, match):
    with pytest.raises(ValueError, match=match):
        check_lidar_study(study(**kw))


def test_multi_round_planning_on_a_moving_platform_needs_planned_cells():
    # the steered beam's and the micromirror's rounds continue the trajectory; a flash
    # measures its receiver pixels and is refused with or without motion
    motion = {"kind": "descent", "descent_rate_m_s": 2.0}
    check_lidar_study(study(planners=["sequential"], options={"motion": motion}))
    check_lidar_study(study(sensor="micromirror_flash", planners=["sequential"],
                            options={"motion": motion}))  # fmt: skip
    with pytest.raises(ValueError, match="a flash LIDAR measures its receiver pixels"):
        check_lidar_study(study(sensor="flash", planners=["sequential"],
                                options={"motion": motion}))  # fmt: skip


@pytest.mark.parametrize("sensor", ["steered_beam", "micromirror_flash"])
def test_the_gain_control_is_refused_before_the_render_off_a_flash(sensor):
    # the library refuses it inside the scan (after the render); the schema names the key
    apd = {"detector": {"apd": {"full_scale_pe": 1000.0, "agc_target": 0.5}}}
    with pytest.raises(ValueError, match=rf"apd.agc_target: .* a {sensor} has none"):
        check_lidar_study(study(sensor=sensor, options=apd))
    check_lidar_study(study(sensor="flash", options=apd))
