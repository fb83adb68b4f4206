"""N-step phase shifting with temporal unwrapping: formulas, round trips, noise statistics
against the closed form, unwrapping over the whole projector, validity, and scans of exact
synthetic planes (NumPy capture, no Mitsuba)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from simlunar.scanner import fringes, rigs
from simlunar.scanner import phase_shift as ps
from simlunar.scanner.phase_shift import PhaseShiftOptions
from simlunar.sensors import StructuredLight, StructuredLightOptions
from tests.scanner._synthetic import PlaneCapture


def _frames_at(u, n_axis, o: PhaseShiftOptions, *, a=0.1, c=0.8):
    """Frames of one axis seen by camera pixels at continuous projector coordinates ``u``,
    written from the documented pattern (module docstring), independently of ``encode``:
    ``black + c (1/2 + 1/2 cos(2 pi (u + off) / p + 2 pi n / N))``."""
    periods = fringes.fringe_periods(n_axis, o.period_px, o.ratio)
    off = (periods[0] - n_axis) / 2
    out = []
    for p in periods:
        for n in range(o.steps):
            out.append(
                a + c * (0.5 + 0.5 * np.cos(2 * np.pi * (u + off) / p + 2 * np.pi * n / o.steps))
            )
    return np.stack(out), periods  # fmt: skip


@pytest.mark.parametrize("shape", [(48, 64), (37, 203)])
@pytest.mark.parametrize("steps", [3, 4, 5])
def test_decode_of_encode_is_every_pixel_centre(shape, steps):
    # a camera that sees the projector pixel for pixel, noiseless: every pixel decodes to its
    # own centre (col + 0.5, row + 0.5)
    o = PhaseShiftOptions(steps=steps, period_px=6.0, ratio=5.0)
    H, W = shape
    stack = ps.encode(shape, o)
    assert stack.shape == (len(ps.frame_names(o, shape)) - 2, H, W) and stack.dtype == np.float32
    assert 0.0 <= stack.min() and stack.max() <= 1.0
    dec = ps.decode(stack, np.ones(shape), np.zeros(shape), proj_shape=shape, options=o)
    assert dec.valid.all()
    rr, cc = np.mgrid[0:H, 0:W]
    np.testing.assert_allclose(dec.u, cc + 0.5, atol=1e-4)  # float32 patterns
    np.testing.assert_allclose(dec.v, rr + 0.5, atol=1e-4)
    np.testing.assert_array_equal(dec.col, cc)
    np.testing.assert_array_equal(dec.row, rr)
    np.testing.assert_allclose(dec.modulation, 0.5, atol=1e-5)  # B = contrast / 2


def test_unwrapping_is_right_at_sub_pixel_positions_over_the_whole_width():
    # 1000 columns, 3 levels (periods 1152, 96, 8 px): every sub-pixel position across the whole
    # projector decodes to itself (no fringe-order error anywhere, ends included)
    o = PhaseShiftOptions(steps=4, period_px=8.0, ratio=12.0, axes="cols")
    W = 1000
    u = np.linspace(0.0, W, 20001, endpoint=False)[None, :]  # (1, n) camera "pixels"
    frames, periods = _frames_at(u, W, o)
    assert len(periods) == 3
    dec = ps.decode(
        frames, np.full(u.shape, 0.9), np.full(u.shape, 0.1), proj_shape=(2, W), options=o
    )
    assert dec.valid.all()
    np.testing.assert_allclose(dec.u, u, atol=1e-9)
    assert np.isnan(dec.v).all() and (dec.row == -1).all()


def test_positional_uncertainty_of_noisy_frames_is_the_finest_period_times_the_phase_noise():
    # the decoded column's noise is p_L sigma_phi / (2 pi) and no pixel is unwrapped wrongly
    o = PhaseShiftOptions(steps=4, period_px=8.0, ratio=8.0, axes="cols")
    W, n, sigma = 256, 30_000, 0.01
    rng = np.random.default_rng(1)
    u = rng.uniform(0, W, (1, n))
    frames, periods = _frames_at(u, W, o, a=0.1, c=0.8)  # B = 0.4
    frames = frames + rng.normal(0, sigma, frames.shape)
    dec = ps.decode(
        frames, np.full(u.shape, 0.9), np.full(u.shape, 0.1), proj_shape=(2, W), options=o
    )
    err = dec.u - u
    assert np.all(np.abs(err) < 1.0) and dec.valid.mean() > 0.999
    want = periods[-1] * fringes.phase_noise_std(o.steps, sigma, 0.4) / (2 * np.pi)
    assert np.std(err[dec.valid]) == pytest.approx(want, rel=0.03)


def test_validity_from_light_modulation_and_unwrapping():
    o = PhaseShiftOptions(steps=4, period_px=8.0, ratio=8.0, axes="cols", min_modulation=0.05)
    W = 64
    u = np.array([[10.2, 20.7, 30.1, 40.5]])
    frames, periods = _frames_at(u, W, o, a=0.1, c=0.8)
    white, black = np.full(u.shape, 0.9), np.full(u.shape, 0.1)
    # pixel 1: projector shadow (white = black); pixel 2: weak modulation at the finest level
    # (blur); pixel 3: coarse phase corrupted by a quarter fringe of the next level
    white[0, 1] = black[0, 1]
    fine = slice(len(frames) - o.steps, len(frames))
    frames[fine, 0, 2] = 0.5 + 0.04 * (frames[fine, 0, 2] - 0.5)
    # level 0 (period 512) seen as if at u + 32: its phase off by pi / 8, pi once scaled by 8
    frames[: o.steps, 0, 3] = _frames_at(u + 32, W, o, a=0.1, c=0.8)[0][: o.steps, 0, 3]
    dec = ps.decode(frames, white, black, proj_shape=(2, W), options=o)
    assert dec.valid.tolist() == [[True, False, False, False]]
    assert dec.lit.tolist() == [[True, False, True, True]]
    assert periods == (512.0, 64.0, 8.0)
    assert dec.modulation[0, 2] < 0.05 and dec.disagreement[0, 3] > 1.0
    assert dec.u[0, 0] == pytest.approx(10.2)
    assert dec.col.tolist() == [[10, -1, -1, -1]]
    assert np.isnan(dec.proj_uv()[0, 1:]).all()


def test_decode_reports_missing_frames_and_a_wrong_stack():
    o = PhaseShiftOptions()
    d = ps.PhaseDecoder((8, 16), (4, 4), o)
    with pytest.raises(ValueError, match="missing frames: col0, col1, row0, row1, white/black"):
        d.result()
    with pytest.raises(ValueError, match=r"level frames \(3, 4, 4\) must be \(4, 4, 4\)"):
        d.add_level("col", 0, np.zeros((3, 4, 4)))
    with pytest.raises(ValueError, match="no level 5"):
        d.add_level("col", 5, np.zeros((4, 4, 4)))
    with pytest.raises(ValueError, match=r"must be a \(16, rows, cols\) phase-shift stack"):
        ps.decode(np.zeros((3, 4, 4)), np.ones((4, 4)), np.zeros((4, 4)), proj_shape=(8, 16))


def test_options_are_checked():
    with pytest.raises(ValueError, match="steps must be >= 3"):
        PhaseShiftOptions(steps=2)
    with pytest.raises(ValueError, match="ratio must be > 1"):
        PhaseShiftOptions(ratio=1.0)
    with pytest.raises(ValueError, match="axes must be one of"):
        PhaseShiftOptions(axes="rows")
    with pytest.raises(ValueError, match=r"rays.*needs the row phase"):
        PhaseShiftOptions(axes="cols", method="rays")
    with pytest.raises(ValueError, match="whole number"):
        PhaseShiftOptions(steps=4.5)


def test_frame_names_follow_the_stack_order():
    o = PhaseShiftOptions(steps=3, period_px=8.0, ratio=8.0)
    names = ps.frame_names(o, (48, 50))  # cols: periods (64, 8); rows: (64, 8)
    assert names[:7] == [
        "col0_s0",
        "col0_s1",
        "col0_s2",
        "col1_s0",
        "col1_s1",
        "col1_s2",
        "row0_s0",
    ]
    assert names[-2:] == ["white", "black"] and len(names) == 2 * 2 * 3 + 2


@pytest.fixture
def rig():
    return rigs.moonyard_rig(proj_size=(64, 48), cam_size=(128, 96))


@pytest.mark.parametrize("inverses", ["linearity", "render"])
def test_phase_shift_scan_of_a_plane_matches_truth(rig, inverses):
    cap = PlaneCapture(rig, (0.3, -0.2, 1.0), 0.0, noise=0.002)
    o = PhaseShiftOptions(steps=4, period_px=8.0, ratio=8.0, inverses=inverses)
    g = ps.phase_shift_scan(cap, rig, o)
    levels = sum(len(fringes.fringe_periods(n, 8.0, 8.0)) for n in (64, 48))
    per_level = 2 if inverses == "linearity" else 4  # even N: half the shifts by linearity
    assert g.renders == cap.renders == 2 + levels * per_level
    truth = cap.true_depth(rig.guide)
    ok = np.isfinite(g.depth)
    assert ok.mean() > 0.9
    rel = np.abs(g.depth[ok] - truth[ok]) / truth[ok]
    # the capture samples the projector texture at pixel centres (nearest): the decoded
    # coordinate is the centre of the projector pixel a camera sub-ray sees, averaged over
    # the 3 x 3 sub-rays; the depth error stays within the depth of one projector column
    # (about z / (f_p b) per pixel, 1-2 % here) and is far smaller on average
    assert np.median(rel) < 0.003 and np.percentile(rel, 99) < 0.02
    assert g.coding.options == o and g.frames.keys() == {"white", "black"}


def test_phase_shift_is_a_mode_of_the_scanner_and_runs_under_ambiguity_enhancement(rig):
    cap = PlaneCapture(rig, (0.1, 0.0, 1.0), 0.0)
    sensor = StructuredLight(
        cap, rig, depth_range=(1.0, 3.0), options=StructuredLightOptions("phase_shift")
    )
    assert not sensor.needs_plan
    res = sensor.acquire(None).detail
    assert (
        res.coded.coding.options == PhaseShiftOptions() and np.isfinite(res.measured).mean() > 0.9
    )
    ae = StructuredLight(
        cap,
        rig,
        depth_range=(1.0, 3.0),
        options=StructuredLightOptions("ambiguity_enhancement", coding="phase_shift"),
    )
    acq = ae.acquire(np.array([[10, 10], [20, 30]]))
    assert isinstance(acq.detail.coded.decode, ps.PhaseDecode)
    hit = np.isfinite(acq.detail.dots.depth)
    np.testing.assert_array_equal(acq.detail.measured[hit], acq.detail.dots.depth[hit])


def test_decoding_error_is_measured_against_the_continuous_truth():
    # a decode shifted by a known 0.3 px from the true projector coordinates scores 0.3 px,
    # not the 1/sqrt(12) = 0.289 px of comparing with the true pixel's centre; 1.2 px off is
    # an unwrapping error
    from simlunar.scanner.phase_shift import PhaseDecode, PhaseShiftCoding, coord_scores

    rng = np.random.default_rng(0)
    uv = np.stack([rng.uniform(0, 64, (30, 40)), rng.uniform(0, 48, (30, 40))], axis=-1)
    ones = np.ones((30, 40), bool)
    u = uv[..., 0] + 0.3
    u[0, :4] += 0.9
    dec = PhaseDecode(u=u, v=uv[..., 1] - 0.3, valid=ones, lit=ones, modulation=np.ones((30, 40)),
                      disagreement=np.zeros((30, 40)), contrast=np.ones((30, 40), np.float32),
                      proj_shape=(48, 64))  # fmt: skip
    truth = {"uv": uv, "lit": ones}
    s = coord_scores(dec, truth)
    assert s["coord_rmse_px"] == pytest.approx(0.3, abs=1e-12)
    assert s["coord_err_rate"] == 4 / (30 * 40)
    scan = SimpleNamespace(decode=dec)
    assert PhaseShiftCoding().truth_scores(scan, truth) == s
    # rows are scored too: a row off by more than a pixel is an error
    dec2 = PhaseDecode(**{**dec.__dict__, "v": uv[..., 1] + 1.5})
    assert coord_scores(dec2, truth)["coord_err_rate"] == 1.0
    assert coord_scores(dec2, truth, rows=False)["coord_err_rate"] == 4 / (30 * 40)
