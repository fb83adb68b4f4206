"""The reading options shared by shading and photoclinometry: one declaration, same bounds."""

import dataclasses

import pytest

from simlunar.reconstruction._reading import READING_OPTIONS, check_share_band
from simlunar.reconstruction.photoclinometry import PhotoclinometryOptions
from simlunar.reconstruction.shading import ShadingOptions
from simlunar.registry import option_info


def test_both_option_classes_carry_the_shared_declarations():
    shading, photo = option_info(ShadingOptions), option_info(PhotoclinometryOptions)
    for name, spec in READING_OPTIONS.items():
        assert shading[name] == photo[name], name
        assert shading[name]["default"] == spec["default"]
        assert shading[name]["doc"] == spec["doc"]


@pytest.mark.parametrize("cls", [ShadingOptions, PhotoclinometryOptions])
def test_bounds_and_share_band_are_checked(cls):
    with pytest.raises(ValueError, match="gain must be <= 10"):
        cls(gain=11.0)
    with pytest.raises(ValueError, match=r"share_hi must be > share_lo, got 0\.2 <= 0\.3"):
        cls(share_lo=0.3, share_hi=0.2)
    assert cls(share_lo=0.2, share_hi=0.3).share_hi == 0.3


def test_check_share_band_on_any_object():
    @dataclasses.dataclass
    class Band:
        share_lo: float
        share_hi: float

    check_share_band(Band(0.1, 0.5))
    with pytest.raises(ValueError, match="share_hi must be > share_lo"):
        check_share_band(Band(0.5, 0.5))
