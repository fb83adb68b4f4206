"""The coded-scan helpers and coding bases shared by gray code, phase and micro phase shift."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from simlunar.scanner import coded, rigs
from simlunar.scanner.gray_code import GrayCodeOptions, GrayCoding
from simlunar.scanner.micro_phase_shift import MicroPhaseShiftCoding, MicroPhaseShiftOptions
from simlunar.scanner.phase_shift import PhaseShiftCoding, PhaseShiftOptions


@pytest.fixture
def rig():
    return rigs.moonyard_rig(proj_size=(64, 48), cam_size=(128, 96))


def test_scan_inputs_defaults_the_options_and_checks_the_rig(rig):
    o, (H, W) = coded.scan_inputs(rig, None, GrayCodeOptions)
    assert o == GrayCodeOptions() and (H, W) == rig.projector.intrinsics.shape
    given = GrayCodeOptions(subpixel=True)
    assert coded.scan_inputs(rig, given, GrayCodeOptions)[0] is given
    not_a_projector = SimpleNamespace(camera=rig.camera, projector=rig.camera)
    with pytest.raises(ValueError, match=r"must be a geometry\.Projector"):
        coded.scan_inputs(not_a_projector, None, GrayCodeOptions)


def test_render_checked_refuses_a_wrong_stack():
    class Bad:
        def render(self, patterns):
            return np.zeros((len(patterns) - 1, 2, 2), np.uint8)

    with pytest.raises(ValueError, match=r"returned shape \(1, 2, 2\) for 2 patterns"):
        coded.render_checked(Bad(), np.zeros((2, 2, 2), np.float32))

    class Good:
        def render(self, patterns):
            return np.ones((len(patterns), 2, 2), np.uint8)

    out = coded.render_checked(Good(), np.zeros((3, 2, 2), np.float32))
    assert out.dtype == np.float64 and out.shape == (3, 2, 2)


@pytest.mark.parametrize(
    "coding",
    [PhaseShiftCoding(PhaseShiftOptions()), MicroPhaseShiftCoding(MicroPhaseShiftOptions())],
)
def test_white_black_last_stack_and_its_decode_shape(coding):
    shape = (8, 12)
    pats = coding.patterns(shape)
    assert pats.dtype == np.float32 and pats.shape[1:] == shape
    assert len(pats) == coding.frames(shape) == len(coding.frame_names(shape))
    np.testing.assert_array_equal(pats[-2], 1.0)  # white, then black, last
    np.testing.assert_array_equal(pats[-1], 0.0)
    dec = coding.decode(pats, shape)  # the projector looking at itself
    assert dec.valid.shape == shape


def test_scan_keeps_frames_when_asked_without_changing_the_coding():
    seen = []
    gray = GrayCoding(GrayCodeOptions())
    gray._scan = lambda capture, rig, o: seen.append(o) or o  # the instance's scan function
    assert gray.scan(None, None, keep_frames=True).keep_frames is True
    assert gray.scan(None, None).keep_frames is False and gray.options.keep_frames is False
    assert isinstance(gray, coded.FullFieldCoding) and gray.full_field and gray.method == "plane"
