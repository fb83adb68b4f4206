"""Name checks against the components' own registries: valid names come from the registries
(a newly registered strategy is usable at once), errors name the key path and list the valid
names sorted; oracles and measuring strategies are no scanner planners; labels name their base."""

from __future__ import annotations

import pytest

from simlunar.config import registry
from simlunar.config.planners import StrategyOptionsCfg
from simlunar.config.terrain import preset_names as shipped_presets
from simlunar.errors import ConfigError
from simlunar.metrics import METRICS
from simlunar.planner import MEASURING, ORACLES, STRATEGIES
from simlunar.scanner.rescan import SCAN_PLANNERS
from simlunar.sensors.structured_light import MODES


def test_names_come_from_the_components():
    assert registry.strategy_names() == [*STRATEGIES, *MEASURING]
    assert registry.metric_names() == list(METRICS)
    assert registry.preset_names() == shipped_presets()


def test_a_newly_registered_strategy_is_valid_at_once(monkeypatch):
    with pytest.raises(ConfigError):
        registry.check_strategy("brand_new", "study.strategies[0]")
    monkeypatch.setitem(STRATEGIES._entries, "brand_new", STRATEGIES["random"])
    registry.check_strategy("brand_new", "study.strategies[0]")
    registry.check_scan_planner("brand_new", "study.planners[0]")


def test_an_unknown_name_lists_the_valid_ones_sorted():
    valid = ", ".join(sorted({*STRATEGIES, *MEASURING}))
    with pytest.raises(ConfigError) as info:
        registry.check_strategy("wavlet", "study.strategies[1]")
    assert str(info.value) == (
        f"study.strategies[1]: unknown strategy 'wavlet' (valid: {valid}) (did you mean 'wavelet'?)"
    )
    with pytest.raises(ConfigError) as info:
        registry.check_metric("mse2", "study.metrics[0]")
    assert (
        str(info.value)
        == f"study.metrics[0]: unknown metric 'mse2' (valid: {', '.join(sorted(METRICS))})"
        " (did you mean 'mse'?)"
    )
    with pytest.raises(
        ConfigError, match=r"^study\.modes\[0\]: unknown scan mode 'laser' \(valid: "
    ):
        registry.check_scan_mode("laser", "study.modes[0]")
    for mode in MODES:
        registry.check_scan_mode(mode, "study.modes[0]")


def test_a_label_is_checked_by_its_base_strategy():
    opts = {"w_bn": StrategyOptionsCfg(strategy="wavelet", blue_noise=True),
            "bad": StrategyOptionsCfg(strategy="wavlet")}  # fmt: skip
    registry.check_strategy("w_bn", "study.strategies[2]", opts)
    with pytest.raises(
        ConfigError, match=r"^study\.strategies\[3\] \(bad\)\.strategy: unknown strategy 'wavlet'"
    ):
        registry.check_strategy("bad", "study.strategies[3]", opts)
    # a label without a base strategy must itself be one
    with pytest.raises(ConfigError, match="unknown strategy 'w_plain'"):
        registry.check_strategy("w_plain", "study.strategies[0]", opts)


def test_scanner_planners_plan_from_the_image_alone():
    for name in (*ORACLES, *MEASURING):
        with pytest.raises(ConfigError) as info:
            registry.check_scan_planner(name, "study.planners[0]")
        assert str(info.value) == (
            f"study.planners[0]: {name!r} is a planner of the sampling study only (the scanner "
            "study gives no planner the truth or a sensor to ask back)"
        )
    for name in (*SCAN_PLANNERS, "wavelet", "grid"):
        registry.check_scan_planner(name, "study.planners[0]")


def test_presets_by_name_or_file(tmp_path):
    registry.check_preset("aerial_1", "terrain.preset")
    with pytest.raises(
        ConfigError,
        match=r"^terrain\.preset: unknown terrain preset 'aerial_9' \(valid: aerial_1, ",
    ):
        registry.check_preset("aerial_9", "terrain.preset")
    f = tmp_path / "mine.yaml"
    with pytest.raises(ConfigError, match=f"^terrain.preset: preset file not found: {f}$"):
        registry.check_preset(str(f), "terrain.preset")
    f.write_text("grid: {}\n")
    registry.check_preset(str(f), "terrain.preset")  # its contents are the preset's models' job
