"""The study models, built directly: log-spaced density ranges, unique names, each strategy's
options checked with the path of the label, oracles labelled as bounds, a LIDAR reading only its
own options block."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from simlunar.config.studies import (
    LIDAR_BLOCKS,
    DensityRange,
    LidarStudyCfg,
    SamplingStudyCfg,
)


def _msg(cls, **kw) -> str:
    with pytest.raises(ValidationError) as info:
        cls(**kw)
    return info.value.errors()[0]["msg"]


def test_a_density_range_is_log2_spaced_with_its_ends():
    r = DensityRange.model_validate({"from": "1/2", "to": "1/8", "count": 3})
    assert r.values() == [0.5, 0.25, 0.125]
    assert DensityRange.model_validate({"from": 0.5, "to": 0.5, "count": 1}).values() == [0.5]
    # 1/2 .. 1/2048 in 11 steps is exactly the powers of two (the paper's section 4.1)
    big = DensityRange.model_validate({"from": "1/2", "to": "1/2048", "count": 11}).values()
    assert big == [2.0**-i for i in range(1, 12)]
    with pytest.raises(ValidationError, match="Field required"):
        DensityRange.model_validate({"start": 0.5, "stop": 0.1, "count": 2})  # the keys are from/to
    with pytest.raises(ValidationError, match="less than or equal to 64"):
        DensityRange.model_validate({"from": 0.5, "to": 0.1, "count": 65})


def test_a_study_takes_a_list_or_a_range_of_densities():
    s = SamplingStudyCfg(densities={"from": "1/4", "to": "1/16", "count": 2})
    assert s.densities == [0.25, 0.0625]
    assert SamplingStudyCfg(densities=["1/2", 0.1]).densities == [0.5, 0.1]
    assert s.strategies == ["random", "grid", "gradient", "entropy", "wavelet"]
    assert (s.trials, s.metrics, s.score_region, s.terrain_seeds) == (
        20,
        ["mse", "grad", "sal"],
        "full",
        1,
    )
    assert "at least 1 item" in _msg(SamplingStudyCfg, densities=[])


def test_names_are_unique():
    assert _msg(SamplingStudyCfg, densities=[0.5], strategies=["grid", "grid"]) == (
        "Value error, names must be unique, got ['grid', 'grid']"
    )
    assert "names must be unique" in _msg(LidarStudyCfg, kind="lidar", metrics=["mse", "mse"])


def test_strategy_options_are_checked_with_the_label_in_the_path():
    ok = SamplingStudyCfg(
        densities=[0.5],
        strategies=["random", "wavelet_bn"],
        strategy_options={"wavelet_bn": {"strategy": "wavelet", "blue_noise": True}},
    )
    assert ok.strategy_options["wavelet_bn"].blue_noise
    assert (
        _msg(
            SamplingStudyCfg,
            densities=[0.5],
            strategies=["w"],
            strategy_options={"w": {"strategy": "wavelet", "coefficients": {"wavelet": 1}}},
        )
        == "Value error, strategy_options.w.coefficients: only the combination strategy takes them ('wavelet')"
    )
    # a strategy without options block is checked with the defaults, named by its list entry
    assert _msg(SamplingStudyCfg, densities=[0.5], strategies=["combination"]) == (
        "Value error, strategies (combination).coefficients: strategy 'combination' needs at "
        "least one weight"
    )


def test_an_oracle_label_starts_with_oracle_and_unknown_names_are_left_to_the_registries():
    assert _msg(
        SamplingStudyCfg,
        densities=[0.5],
        strategies=["bound"],
        strategy_options={"bound": {"strategy": "oracle_hessian"}},
    ) == (
        "Value error, strategy_options.bound: a label of an oracle (oracle_hessian) starts "
        "with 'oracle', so every table shows it as a bound"
    )
    SamplingStudyCfg(densities=[0.5], strategies=["oracle_tight"],
                     strategy_options={"oracle_tight": {"strategy": "oracle_hessian"}})  # fmt: skip
    SamplingStudyCfg(densities=[0.5], strategies=["no_such_planner"])  # reported elsewhere


def test_a_lidar_reads_only_its_own_options_block():
    assert set(LIDAR_BLOCKS) == set(LidarStudyCfg.model_fields["sensor"].annotation.__args__)
    s = LidarStudyCfg(kind="lidar", sensor="flash", options={"flash": {"revisits": 2}})
    assert s.options.flash.revisits == 2
    assert s.densities == [1 / 64, 1 / 256] and s.planners == ["wavelet", "random", "grid"]
    assert (
        _msg(
            LidarStudyCfg, kind="lidar", sensor="flash", options={"steered_beam": {"settle_ms": 2}}
        )
        == "Value error, options.steered_beam: not an option of the flash sensor (set options.flash)"
    )
    assert _msg(
        LidarStudyCfg, kind="lidar", sensor="micromirror_flash", options={"flash": {"zoom": 2}}
    ) == (
        "Value error, options.flash: not an option of the micromirror_flash sensor "
        "(set options.micromirror)"
    )


def test_lidar_planner_options_belong_to_its_planners():
    assert _msg(LidarStudyCfg, kind="lidar", planners=["grid"],
                planner_opts={"wavelet": {}}) == (
        "Value error, planner_opts.wavelet: not in study.planners (grid)"
    )  # fmt: skip
    assert _msg(LidarStudyCfg, kind="lidar", planners=["grid"],
                planner_opts={"grid": {"uniform_mix": 0.5}}) == (
        "Value error, planner_opts.grid.uniform_mix: strategy 'grid' takes no options"
    )  # fmt: skip


def test_an_oracle_reads_the_error_of_one_of_the_studys_reconstructions():
    from simlunar.config import translate

    ok = SamplingStudyCfg(
        densities=[0.5], strategies=["oracle_greedy", "oracle_fused"],
        reconstructions=["linear", {"fused": {"reconstruction": "shading"}}],
        strategy_options={"oracle_fused": {"strategy": "oracle_greedy",
                                           "oracle": {"reconstruction": "fused"}}},
    )  # fmt: skip
    opts = translate.sampling_options(ok).strategy_options
    assert opts["oracle_fused"]["reconstruction"] == "fused"
    msg = _msg(
        SamplingStudyCfg, densities=[0.5], strategies=["oracle_s"],
        strategy_options={"oracle_s": {"strategy": "oracle_greedy",
                                       "oracle": {"reconstruction": "shading"}}},
    )  # fmt: skip
    assert "oracle_s.oracle.reconstruction: 'shading' is not one of study.reconstructions" in msg


# ---- study.options_by_sensor: each sensor of a sweep over study.sensor its own options -----


def _lidar_study(**kw):
    from simlunar.config.studies import LidarStudyCfg

    by = {
        "flash": {"instrument": "alhat_flash", "flash": {"receiver_px": [32, 32]}},
        "steered_beam": {"instrument": "lola_beam", "steered_beam": {"pulses_per_point": 2}},
    }
    return LidarStudyCfg(kind="lidar", options_by_sensor=by, **kw)


def test_options_by_sensor_picks_the_study_sensors_options():
    flash = _lidar_study(sensor="flash")
    assert flash.options.instrument == "alhat_flash"
    assert tuple(flash.options.flash.receiver_px) == (32, 32)
    beam = _lidar_study(sensor="steered_beam")
    assert beam.options.instrument == "lola_beam"
    assert beam.options.steered_beam.pulses_per_point == 2
    # a sweep point: the flash's validated config with the sensor switched
    data = flash.model_dump()
    data["sensor"] = "steered_beam"
    assert type(flash).model_validate(data).options.instrument == "lola_beam"
    # a sensor without an entry keeps options
    mm = _lidar_study(sensor="micromirror_flash")
    assert mm.options.instrument is None


def test_options_beside_options_by_sensor_must_be_one_of_them():
    with pytest.raises(ValidationError, match=r"replaced by options_by_sensor\.flash"):
        _lidar_study(sensor="flash", options={"instrument": "micromirror_flash"})
