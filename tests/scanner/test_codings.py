"""The coding registry: one entry per coding with its options class, and the contract every
registered coding keeps (frame counts, names, round trip of its own patterns, scan)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simlunar.scanner import rigs
from simlunar.scanner.codings import (
    CODINGS,
    DEFAULT_CODING,
    coding_for,
    full_field_codings,
    make_coding,
)
from simlunar.scanner.gray_code import GrayCodeOptions
from simlunar.scanner.result import CodedScan
from simlunar.sensors.structured_light import DOT_MODES, MODES, mode_coding
from tests.scanner._synthetic import PlaneCapture


def test_registry_names_options_and_modes():
    assert DEFAULT_CODING == "gray_code"
    assert set(full_field_codings()) >= {"gray_code", "phase_shift"}
    assert MODES == (*full_field_codings(), *DOT_MODES)
    for entry in CODINGS.values():
        assert dataclasses.is_dataclass(entry.options) and entry.summary
        assert {"full_field", "yaml_key", "label", "style"} <= set(entry.meta)
    assert mode_coding("phase_shift") == "phase_shift"
    assert mode_coding("ambiguity_enhancement", "phase_shift") == "phase_shift"
    assert mode_coding("data_reduction") is None
    with pytest.raises(ValueError, match="unknown scan mode 'grey_code'"):
        mode_coding("grey_code")


def test_make_coding_checks_names_options_and_types():
    with pytest.raises(
        ValueError, match=r"unknown coding 'phase_shfit'.*did you mean 'phase_shift'"
    ):
        make_coding("phase_shfit")
    with pytest.raises(ValueError, match=r"unknown option 'step' of phase_shift.*'steps'"):
        make_coding("phase_shift", {"step": 4})
    with pytest.raises(TypeError, match="takes PhaseShiftOptions, got GrayCodeOptions"):
        make_coding("phase_shift", GrayCodeOptions())
    assert make_coding("phase_shift", {"steps": 5}).options.steps == 5
    opts = {"gray_code": GrayCodeOptions(subpixel=True)}
    assert coding_for(opts, "gray_code").options.subpixel
    assert coding_for(opts, "phase_shift").options == CODINGS["phase_shift"].options()


def test_gray_code_frame_count_is_opencvs():
    # 128 x 96: 7 column + 7 row bits, (pattern, inverse) each, then white and black
    assert make_coding("gray_code").frames((96, 128)) == 2 * (7 + 7) + 2


@pytest.mark.parametrize("name", full_field_codings())
@pytest.mark.parametrize("shape", [(12, 20), (33, 47)])
def test_every_coding_decodes_its_own_patterns_to_the_pixel_centres(name, shape):
    coding = make_coding(name)
    H, W = shape
    pats = coding.patterns(shape)
    names = coding.frame_names(shape)
    assert pats.shape == (coding.frames(shape), H, W) == (len(names), H, W)
    assert names[-2:] == ["white", "black"] and len(set(names)) == len(names)
    np.testing.assert_array_equal(pats[-2], 1.0)
    np.testing.assert_array_equal(pats[-1], 0.0)
    dec = coding.decode(pats, shape)  # a camera that sees the projector pixel for pixel
    rr, cc = np.mgrid[0:H, 0:W]
    assert dec.valid.all() and dec.lit.all() and dec.proj_shape == shape
    np.testing.assert_allclose(dec.proj_uv(), np.stack([cc + 0.5, rr + 0.5], -1), atol=1e-4)
    np.testing.assert_array_equal(dec.col, cc)
    np.testing.assert_array_equal(dec.decoded_index()[1], rr)


@pytest.mark.parametrize("name", full_field_codings())
def test_every_coding_scans_a_plane_keeping_its_frames_on_request(name):
    rig = rigs.moonyard_rig(proj_size=(32, 24), cam_size=(64, 48))
    coding = make_coding(name)
    cap = PlaneCapture(rig, (0.0, 0.0, 1.0), 0.0)
    scan = coding.scan(cap, rig, keep_frames=True)
    kept = dataclasses.replace(coding.options, keep_frames=True)
    assert isinstance(scan, CodedScan) and scan.coding.options == kept
    assert (
        len(scan.frames["images"]) + 2
        == coding.frames((24, 32))
        == len(coding.frame_names((24, 32)))
    )
    assert scan.renders == cap.renders <= coding.frames((24, 32))
    truth = cap.true_depth(rig.guide)
    ok = np.isfinite(scan.depth)
    # within about one projector column's depth (the gray code quantises to columns; 32 px)
    assert ok.mean() > 0.9 and np.median(np.abs(scan.depth[ok] - truth[ok]) / truth[ok]) < 0.03
    meta = coding.export_meta(scan.decode)
    assert meta["triangulation"] == coding.method
    assert "images" not in coding.scan(cap, rig).frames  # kept only on request
