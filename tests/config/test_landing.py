"""Landing-question configuration (simlunar.config.landing)."""

from __future__ import annotations

from dataclasses import asdict

import pytest
from pydantic import TypeAdapter, ValidationError

from simlunar.config import lidar
from simlunar.config.landing import HazardCfg, MedianWindowPx, SafeSiteCfg, SlopeBaselinePx
from simlunar.metrics.hazard import HazardOptions


def test_hazard_defaults_and_units():
    assert HazardCfg().model_dump() == asdict(HazardOptions())
    h = HazardCfg(relief_m="25 cm", slope_deg="0.25 rad")
    assert h.relief_m == pytest.approx(0.25) and h.slope_deg == pytest.approx(14.32394487827058)
    with pytest.raises(ValidationError, match=r"must be odd \(a centred window\), got 16"):
        HazardCfg(window_px=16)
    with pytest.raises(ValidationError, match="less than 90"):
        HazardCfg(slope_deg=90)


def test_safe_site_thresholds_and_units():
    s = SafeSiteCfg()
    assert (s.slope_deg, s.rock_height_m, s.semi_axes_m) == (12.0, 0.3, (4.0, 4.0))
    s = SafeSiteCfg(rock_height_m="20 cm", pitch_m="0.01 km")
    assert s.rock_height_m == pytest.approx(0.2) and s.pitch_m == pytest.approx(10.0)
    with pytest.raises(ValidationError, match=r"must be odd \(a centred window\), got 4"):
        SafeSiteCfg(window_px=4)
    with pytest.raises(ValidationError, match="less than 1"):
        SafeSiteCfg(max_hazard_fraction=1.0)


def test_lidar_re_exports_the_landing_models():
    assert lidar.HazardCfg is HazardCfg and lidar.SafeSiteCfg is SafeSiteCfg


@pytest.mark.parametrize(
    ("key", "kind", "edge", "value", "error"),
    [
        ("window_px", MedianWindowPx, 3, 2, "greater than or equal to 3"),
        ("window_px", MedianWindowPx, 255, 257, "less than or equal to 255"),
        ("window_px", MedianWindowPx, 9, 8, r"must be odd \(a centred window\), got 8"),
        ("baseline_px", SlopeBaselinePx, 1, 0, "greater than 0"),
        ("baseline_px", SlopeBaselinePx, 64, 65, "less than or equal to 64"),
    ],
)
def test_window_and_baseline_types_bound_both_models(key, kind, edge, value, error):
    assert TypeAdapter(kind).validate_python(edge) == edge
    with pytest.raises(ValidationError, match=error):
        TypeAdapter(kind).validate_python(value)
    for model in (HazardCfg, SafeSiteCfg):
        assert getattr(model(**{key: edge}), key) == edge
        with pytest.raises(ValidationError, match=error):
            model(**{key: value})


def test_landing_block_translates_to_the_metric_options():
    from simlunar.config.landing import LandingCfg
    from simlunar.config.lidar_translate import landing_options
    from simlunar.metrics.landing import LandingOptions

    assert landing_options(None) is None
    assert landing_options(LandingCfg()) == LandingOptions()
    got = landing_options(LandingCfg(rock_heights_m=["20 cm"], footprint_m="0.006 km"))
    assert got.rock_heights_m == pytest.approx((0.2,)) and got.footprint_m == pytest.approx(6.0)
    with pytest.raises(ValidationError, match="greater than 0"):
        LandingCfg(rock_heights_m=[0.0])
    with pytest.raises(ValidationError, match="at least 1"):
        LandingCfg(rock_heights_m=[])
