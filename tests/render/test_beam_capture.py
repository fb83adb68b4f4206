"""Steered beams (mitransient): planes at known range, footprint broadening, one kernel for every
batch, sub-bin ranges."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import (
    FootprintOptions,
    PulseOptions,
    TimeBins,
    extract_ranges,
)
from tests.render._transient_planes import H, _plane, _read

pytestmark = pytest.mark.render


def test_steered_beams_plane_within_one_bin(mi):
    from simlunar.render.beam_capture import BeamCapture, capture_beams

    rng = np.random.default_rng(0)
    ang = rng.uniform(-0.3, 0.3, (40, 2))
    d = np.stack([np.tan(ang[:, 0]), np.tan(ang[:, 1]), -np.ones(40)], axis=1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    window = TimeBins(0.0, 0.1, 60)  # 3 m per batch window
    cap = BeamCapture(
        _plane(),
        [0.0, 0.0, H],
        footprint=FootprintOptions(1e-4, samples=4),
        window=window,
        batch=16,
    )
    truth = H / -d[:, 2]
    assert cap.cast(d) == pytest.approx(truth, rel=1e-5)
    # gated around the plane z = 0.3 (a reference 0.3 m off the ground): margins cover it
    pred = (H - 0.3) / -d[:, 2]
    ret = capture_beams(cap, d, pred, margin_m=0.5)
    res = _read(ret.binned, window)
    got = res.range + ret.start_opl / 2.0
    assert res.valid.all()
    assert np.abs(got - truth).max() < window.bin_range


@pytest.mark.parametrize("profile", ["uniform", "gaussian"])
def test_tilted_plane_return_broadens_as_the_footprint_predicts(mi, profile):
    from simlunar.lidar import tilted_plane_spread
    from simlunar.render.beam_capture import BeamCapture, capture_beams
    from simlunar.render.transient import TransientOptions

    theta = np.radians(45.0)
    fp = FootprintOptions(divergence_rad=0.02, profile=profile, samples=1024)
    window = TimeBins(0.0, 0.01, 600)  # 5 mm range bins over 3 m
    cap = BeamCapture(
        _plane(slope=np.tan(theta), size=20.0, spacing=0.5),
        [0.0, 0.0, H],
        footprint=fp,
        window=window,
        options=TransientOptions(seed=3),
        batch=4,
    )
    ret = capture_beams(cap, np.array([[0.0, 0.0, -1.0]] * 4), np.full(4, H), margin_m=1.0)
    h = ret.binned.sum(axis=0)
    r = ret.start_opl[0] / 2 + window.centres_range
    mean = np.sum(h * r) / h.sum()
    sd = np.sqrt(np.sum(h * (r - mean) ** 2) / h.sum())
    # the beam meets the plane at R = H (the plane passes through the origin's nadir point)
    # with incidence 45 deg: range std = R tan(theta) std(offset)
    # by hand: uniform disk of half-angle 0.01 rad: per-axis std 0.005 rad -> 50 * 0.005;
    # Gaussian sigma 0.005 rad truncated at 3 sigma: per-axis std
    # 0.005 * sqrt(1 - 4.5 e^-4.5 / (1 - e^-4.5)) = 0.004872 rad -> 0.2436 m
    want = tilted_plane_spread(H, theta, fp)
    assert want == pytest.approx(0.25 if profile == "uniform" else 0.2436, rel=1e-3)
    assert sd == pytest.approx(want, rel=0.05)
    assert mean == pytest.approx(H, abs=0.02)


def test_batches_reuse_one_kernel(mi):
    import drjit as dr

    from simlunar.render.beam_capture import BeamCapture

    cap = BeamCapture(
        _plane(),
        [0.0, 0.0, H],
        footprint=FootprintOptions(1e-3, samples=4),
        window=TimeBins(0.0, 0.1, 40),
        batch=8,
    )
    d = np.tile([[0.0, 0.0, -1.0]], (8, 1))
    cap.render_batch(d, 96.0)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()
        d2 = d + np.array([0.05, 0.0, 0.0])
        h, _ = cap.render_batch(d2[:5], 97.0, seed=1)
        compiled = [
            e
            for e in dr.kernel_history()
            if e.get("type") == dr.KernelType.JIT and not e.get("cache_hit", 0)
        ]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert compiled == []
    h = h.reshape(5, 40, cap.oversample).sum(-1)
    assert h.shape == (5, 40)
    # the window moved by 1 m of OPL: the return (OPL 2 * 50.06 m) sits at bin (100.12 - 97) / 0.1
    assert int(np.argmax(h[0])) == 31


def test_rendered_plane_keeps_the_sub_bin_range(mi):
    # beams at incidence angles that put a plane's range at 10 offsets across one 5 cm bin: the
    # noise-free reading of the rendered (tent-splatted, oversampled) return through a 1 ns pulse
    # is within 1 mm at every offset. A box-binned film snaps them to the bin centre
    # (+25 ... -19 mm: docs/lidar.md, "How a return is made", step 3).
    from simlunar.lidar import shape_waveform
    from simlunar.render.beam_capture import BeamCapture, capture_beams

    offsets = (np.arange(10) + 0.05) / 10
    truth = 50.0 + offsets * 0.05
    theta = np.arccos(H / truth)
    d = np.stack([np.sin(theta), np.zeros(10), -np.cos(theta)], axis=1)
    window = TimeBins(0.0, 0.1, 60)
    cap = BeamCapture(
        _plane(),
        [0.0, 0.0, H],
        footprint=FootprintOptions(1e-6, samples=4),
        window=window,
        batch=16,
    )
    ret = capture_beams(cap, d, truth.round(1), margin_m=0.5)
    pulse = PulseOptions(fwhm_s=1e-9, jitter_s=0.1e-9)
    lam = shape_waveform(ret.histograms, window, pulse, oversample=ret.oversample)
    lam = 1000 * lam / lam.sum(-1, keepdims=True) + 0.01
    res = extract_ranges(lam, window, pulse=pulse)
    got = res.range + ret.start_opl / 2.0
    assert res.valid.all()
    assert np.abs(got - truth).max() < 1e-3
