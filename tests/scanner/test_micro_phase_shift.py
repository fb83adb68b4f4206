"""Micro phase shifting: round trips over the whole axis, the repeat length it refuses beyond,
noise, validity, and scans of exact synthetic planes (NumPy capture, no Mitsuba)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import micro_phase_shift as mps
from simlunar.scanner import rigs
from simlunar.scanner.micro_phase_shift import MicroPhaseShiftOptions
from simlunar.sensors import StructuredLight, StructuredLightOptions
from tests.scanner._synthetic import PlaneCapture


def _frames_at(u, o: MicroPhaseShiftOptions, *, a=0.1, c=0.8):
    """Frames of one axis at continuous projector coordinates ``u``, from the documented
    patterns (module docstring), independently of ``encode``."""
    f = mps.frequencies(o)
    out = [a + c * (0.5 + 0.5 * np.cos(2 * np.pi * f[0] * u + 2 * np.pi * s / 3)) for s in range(3)]
    out += [a + c * (0.5 + 0.5 * np.cos(2 * np.pi * fj * u)) for fj in f[1:]]
    return np.stack(out)


def test_frequencies_span_the_band():
    o = MicroPhaseShiftOptions(period_px=16.0, band=0.1, frequencies=5)
    f = mps.frequencies(o)
    np.testing.assert_allclose(f, np.array([0.95, 0.975, 1.0, 1.025, 1.05]) / 16.0)
    assert mps.unambiguous_px(o) == pytest.approx(640.0)  # 1 / (0.025 / 16)


@pytest.mark.parametrize("shape", [(24, 32), (37, 203)])
def test_decode_of_encode_is_every_pixel_centre(shape):
    o = MicroPhaseShiftOptions()
    H, W = shape
    stack = mps.encode(shape, o)
    assert stack.shape == (2 * (o.frequencies + 2), H, W)
    dec = mps.decode(stack, np.ones(shape), np.zeros(shape), proj_shape=shape, options=o)
    rr, cc = np.mgrid[0:H, 0:W]
    assert dec.valid.all()
    np.testing.assert_allclose(dec.u, cc + 0.5, atol=1e-4)
    np.testing.assert_allclose(dec.v, rr + 0.5, atol=1e-4)


def test_sub_pixel_positions_over_the_whole_unambiguous_length_and_the_refusal_beyond():
    o = MicroPhaseShiftOptions(frequencies=5, axes="cols")  # 640 px unambiguous
    W = 640
    u = (np.arange(12800) + 0.5)[None, :] * (W / 12800)
    frames = _frames_at(u, o)
    dec = mps.decode(
        frames, np.full(u.shape, 0.9), np.full(u.shape, 0.1), proj_shape=(2, W), options=o
    )
    assert dec.valid.all()
    np.testing.assert_allclose(dec.u, u, atol=1e-9)
    with pytest.raises(ValueError, match="repeats every 640 px, shorter than the 1024-px"):
        mps.encode((2, 1024), o)


def test_noise_only_moves_the_coordinate_by_the_phase_noise():
    # no pixel is matched to a wrong period at moderate noise; the sub-pixel error is the
    # three-step phase noise of f0: sqrt(2 / 3) sigma / A periods
    o = MicroPhaseShiftOptions(axes="cols")
    W, n, sigma = 256, 20_000, 0.005
    rng = np.random.default_rng(2)
    u = rng.uniform(0, W, (1, n))
    frames = _frames_at(u, o) + rng.normal(0, sigma, (o.frequencies + 2, 1, n))
    dec = mps.decode(
        frames, np.full(u.shape, 0.9), np.full(u.shape, 0.1), proj_shape=(2, W), options=o
    )
    assert dec.valid.mean() > 0.999
    err = (dec.u - u)[dec.valid]
    assert np.abs(err).max() < 0.5
    want = np.sqrt(2 / 3) * sigma / 0.4 / (2 * np.pi * mps.frequencies(o)[0])
    assert np.std(err) == pytest.approx(want, rel=0.05)


def test_unlit_and_unmodulated_pixels_are_invalid():
    o = MicroPhaseShiftOptions(axes="cols", min_modulation=0.05)
    u = np.array([[10.3, 20.6, 30.2]])
    frames = _frames_at(u, o)
    white, black = np.full(u.shape, 0.9), np.full(u.shape, 0.1)
    white[0, 1] = black[0, 1]
    frames[:, 0, 2] = 0.5 + 0.05 * (frames[:, 0, 2] - 0.5)  # amplitude 0.02
    dec = mps.decode(frames, white, black, proj_shape=(2, 64), options=o)
    assert dec.valid.tolist() == [[True, False, False]]
    assert dec.modulation[0, 2] == pytest.approx(0.02)


def test_options_and_stack_errors():
    with pytest.raises(ValueError, match="frequencies must be >= 2"):
        MicroPhaseShiftOptions(frequencies=1)
    with pytest.raises(ValueError, match=r"band must be <= 0\.5"):
        MicroPhaseShiftOptions(band=0.8)
    with pytest.raises(ValueError, match=r"\(14, rows, cols\) micro phase-shift stack"):
        mps.decode(np.zeros((3, 4, 4)), np.ones((4, 4)), np.zeros((4, 4)), proj_shape=(8, 16))


def test_micro_phase_shift_scans_a_plane_as_a_scanner_mode():
    rig = rigs.moonyard_rig(proj_size=(64, 48), cam_size=(128, 96))
    cap = PlaneCapture(rig, (0.3, -0.2, 1.0), 0.0, noise=0.002)
    sensor = StructuredLight(
        cap, rig, depth_range=(1.0, 3.0), options=StructuredLightOptions("micro_phase_shift")
    )
    res = sensor.acquire(None).detail
    assert res.renders == cap.renders == 2 * (5 + 2) + 2
    truth = cap.true_depth(rig.guide)
    ok = np.isfinite(res.measured)
    assert ok.mean() > 0.9
    rel = np.abs(res.measured[ok] - truth[ok]) / truth[ok]
    assert np.median(rel) < 0.003 and np.percentile(rel, 99) < 0.02
