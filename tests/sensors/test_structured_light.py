"""The structured-light sensor's modes, with the scans replaced by recorders (the scans have
their own tests): the gray code made once and shared, dots replacing gray-code depth where they
were found, data reduction measuring the dots only, planned pixels at projector pixel centres."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from simlunar.scanner.codings import DEFAULT_CODING, full_field_codings
from simlunar.scanner.rigs import aerial_rig
from simlunar.sensors import structured_light as sl
from simlunar.sensors.base import Acquisition

SHAPE = (4, 5)


@pytest.fixture
def scans(monkeypatch):
    calls = {"gray": 0, "dots": []}
    gray_depth = np.full(SHAPE, 10.0)
    gray_depth[0, 0] = np.nan  # a pixel the gray code did not decode

    class FakeCoding:
        def scan(self, capture, rig, *, keep_frames=False):
            calls["gray"] += 1
            return SimpleNamespace(depth=gray_depth.copy(), renders=22)

    def fake_dots(capture, rig, uv, *, depth_range, options):
        calls["dots"].append((uv.copy(), depth_range))
        depth = np.full(SHAPE, np.nan)
        depth[1, 2] = 7.0  # one dot found; the other planned pixel's dot was not
        return SimpleNamespace(depth=depth, renders=3)

    monkeypatch.setattr(sl, "make_coding", lambda name, options=None: FakeCoding())
    monkeypatch.setattr(sl, "dot_scan", fake_dots)
    return calls


def _sensor(mode):
    rig = aerial_rig(proj_size=(SHAPE[1], SHAPE[0]))
    return sl.StructuredLight(None, rig, depth_range=(90.0, 110.0),
                              options=sl.StructuredLightOptions(mode=mode))  # fmt: skip


RC = np.array([[1, 2], [3, 4]])


def test_gray_code_needs_no_plan_and_is_scanned_once(scans):
    s = _sensor("gray_code")
    assert not s.needs_plan and s.proj_shape == SHAPE
    a = s.acquire(None)
    b = s.acquire(None)
    assert scans["gray"] == 1  # shared by every acquisition
    assert (
        isinstance(a, Acquisition) and a.frames == 22 and len(a.values) == SHAPE[0] * SHAPE[1] - 1
    )
    assert a.detail.mode == "gray_code" and a.detail.coded is not None and a.detail.dots is None
    assert b.detail.renders == 22


def test_ambiguity_enhancement_puts_the_dots_over_the_gray_code(scans):
    s = _sensor("ambiguity_enhancement")
    assert s.needs_plan
    a = s.acquire(RC)
    ((uv, depth_range),) = scans["dots"]
    np.testing.assert_array_equal(uv, [[2.5, 1.5], [4.5, 3.5]])  # (c + 1/2, r + 1/2)
    assert depth_range == (90.0, 110.0)
    m = a.measured_map()
    assert m[1, 2] == 7.0  # the dot found replaces the gray code
    assert m[3, 4] == 10.0  # the dot not found keeps the gray-code depth
    assert np.isnan(m[0, 0])
    assert a.frames == 3  # the shared gray code is counted once, by the gray_code mode
    np.testing.assert_array_equal(a.detail.planned_rc, RC)
    s.acquire(RC)
    assert scans["gray"] == 1


def test_data_reduction_measures_the_dots_only(scans):
    a = _sensor("data_reduction").acquire(RC)
    assert scans["gray"] == 0
    np.testing.assert_array_equal(a.rc, [[1, 2]])
    assert a.values.tolist() == [7.0] and a.detail.coded is None


def test_refusals(scans):
    with pytest.raises(
        ValueError, match=r"^scan mode 'data_reduction' rescans planned pixels: rc is required$"
    ):
        _sensor("data_reduction").acquire(None)
    with pytest.raises(
        ValueError, match=r"^unknown scan mode 'laser'; valid: \['ambiguity_enhancement', "
    ):
        sl.StructuredLightOptions(mode="laser")
    # the modes: every full-field coding of the registry, in its order, then the dot modes
    assert sl.MODES == (*full_field_codings(), "ambiguity_enhancement", "data_reduction")
    assert sl.MODES[0] == DEFAULT_CODING
