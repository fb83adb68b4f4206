"""The lidar study's configuration: the shipped experiments, SI translation, one-line errors."""

from __future__ import annotations

from pathlib import Path

import pytest

from simlunar.config.loading import load_experiment
from simlunar.config.yamlio import parse_set
from simlunar.errors import ConfigError

EXPERIMENTS = Path(__file__).resolve().parents[2] / "experiments"
DESCENT = EXPERIMENTS / "lidar_descent_altimeter.yaml"


@pytest.mark.parametrize(
    "name",
    [
        "lidar_descent_altimeter",
        "lidar_descent_micromirror",
        "lidar_hazard_flash",
        "lidar_rover_mast",
    ],
)
def test_the_shipped_lidar_experiments_validate(name):
    cfg = load_experiment(EXPERIMENTS / f"{name}.yaml")
    assert cfg.study.kind == "lidar"


@pytest.mark.parametrize(
    "sets, message",
    [
        (["study.sensor=sonar"], r"study\.sensor"),
        (["study.planners=[wavelet, psychic]", "study.planner_opts={}"],
         r"study\.planners\[1\]: unknown strategy"),
        (["study.metrics=[mse, mse]"], r"study\.metrics"),
        (["study.trials=0"], r"study\.trials"),
        (["study.densities=[2]"], r"study\.densities"),
        (["study.options.pulse.fwhm_ns=-1"], r"study\.options\.pulse\.fwhm_ns"),
        (["study.options.steered_beam.order=spiral"], r"study\.options\.steered_beam\.order"),
        (["study.options.flash.revisits=2"], r"options\.flash: not an option of the steered_beam"),
        (["study.hazard={window_px: 4}"], r"study\.hazard\.window_px: .*odd"),
        (["study.options.detector.expert_signal_photons=5"], r"expert_signal_photons: .*instrument"),
        (["study.options.pulse.fwhm_ns=3"], r"pulse\.fwhm_ns: set by the instrument's hardware"),
        (["study.options.instrument=laser_pointer"], r"study\.options\.instrument"),
        (["study.options.detector.dead_time_ns=2"], r"apd: a linear-mode APD has no dead time"),
        (["study.planner_opts={grid: {uniform_mix: 0.5}}"], r"planner_opts\.grid\.uniform_mix"),
        (["render.camera={kind: orthographic_nadir}"], r"render\.camera: a lidar study needs"),
        (
            ["study.sensor=flash", "study.options.steered_beam={}",
             "study.options.flash={receiver_px: [32, 16]}"],
            r"receiver_px: \(32, 16\) must keep the camera's aspect",
        ),
    ],
)  # fmt: skip
def test_bad_values_are_one_line_errors(sets, message):
    with pytest.raises(ConfigError, match=message) as info:
        load_experiment(DESCENT, parse_set(sets))
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "sets, message",
    [
        # the gate's rule across fields (GateOptions) at load, naming its block
        (["study.options.gate={min_range_m: 50, max_range_m: 40}"],
         r"study\.options\.gate: min_range_m must be < max_range_m"),
        # a divergence is a cone within a hemisphere: below pi/2 rad = 1570796 urad
        (["study.options.hardware.divergence_urad=1.6e6"],
         r"hardware\.divergence_urad: .*less than 1570796"),
        (["study.options.hardware.receiver_px=[0, 4]"], r"hardware\.receiver_px\[0\]: .*greater than or equal to 1"),
    ],
)  # fmt: skip
def test_the_library_rules_fail_at_load(sets, message):
    with pytest.raises(ConfigError, match=message) as info:
        load_experiment(DESCENT, parse_set(sets))
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "sets, message",
    [
        (["study.options.pulse.fwhm_n=3"], r"fwhm_n.*did you mean 'fwhm_ns'"),
        (["study.options.hardware.pulse_energy_j=3"], r"pulse_energy_j.*did you mean 'pulse_energy_uj'"),
        (["study.options.steered_beam.footprint_ray=3"], r"did you mean 'footprint_rays'"),
    ],
)  # fmt: skip
def test_a_misspelt_derived_key_names_the_closest(sets, message):
    with pytest.raises(ConfigError, match=message):
        load_experiment(DESCENT, parse_set(sets))
