"""The options phase shift and micro phase shift share: one declaration, same checks."""

import pytest

from simlunar.registry import option_info
from simlunar.scanner._fringe import FRINGE_OPTIONS, check_rays_axes
from simlunar.scanner.micro_phase_shift import MicroPhaseShiftOptions
from simlunar.scanner.phase_shift import PhaseShiftOptions


def test_both_codings_carry_the_shared_declarations():
    phase, micro = option_info(PhaseShiftOptions), option_info(MicroPhaseShiftOptions)
    for name, spec in FRINGE_OPTIONS.items():
        assert phase[name] == micro[name], name
        assert phase[name]["default"] == spec["default"]
    assert phase["method"]["choices"] == ("plane", "rays")


@pytest.mark.parametrize("cls", [PhaseShiftOptions, MicroPhaseShiftOptions])
def test_rays_need_both_axes_and_choices_are_checked(cls):
    with pytest.raises(ValueError, match="method 'rays' needs the row phase"):
        cls(method="rays", axes="cols")
    assert cls(method="rays", axes="both").method == "rays"
    with pytest.raises(ValueError, match="axes"):
        cls(axes="rows")


def test_check_rays_axes_accepts_the_plane_with_columns_only():
    check_rays_axes(PhaseShiftOptions(axes="cols"))


@pytest.mark.parametrize(("cls", "whole"), [(PhaseShiftOptions, "steps"),
                                            (MicroPhaseShiftOptions, "frequencies")])  # fmt: skip
def test_the_count_option_must_be_whole(cls, whole):
    with pytest.raises(ValueError, match=f"{whole} must be a whole number, got 4.5"):
        cls(**{whole: 4.5})
    assert getattr(cls(**{whole: 4.0}), whole) == 4
