"""Time-of-flight capture (mitransient): planes at known range, footprint broadening, sun."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar import (
    DetectorOptions,
    FootprintOptions,
    PulseOptions,
    TimeBins,
    expected_counts,
    extract_ranges,
    photon_counts,
)
from simlunar.render.lights import SunLight
from simlunar.terrain import Terrain

pytestmark = pytest.mark.render

H = 50.0  # sensor height above the plane (m)
IMPULSE = PulseOptions(fwhm_s=0.0)


def _read(hist, bins):
    """Noise-free ranges of rendered histograms scaled to 1000 photons each."""
    h = np.asarray(hist, float)
    return extract_ranges(1000 * h / h.sum(-1, keepdims=True), bins, pulse=IMPULSE)


def _plane(slope: float = 0.0, size: float = 60.0, spacing: float = 1.0, albedo: float = 0.2):
    n = int(size / spacing)
    x = -size / 2 + (np.arange(n) + 0.5) * spacing
    heights = np.broadcast_to(x[None, :] * slope, (n, n)).copy()
    return Terrain(
        heights=heights,
        albedo=np.full((n, n), albedo, np.float32),
        spacing=spacing,
        origin=(-size / 2, size / 2),
    )


def _nadir_camera(px: int = 16, fov_deg: float = 30.0) -> Camera:
    pose = Pose.look_at([0.0, 0.0, H], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    return Camera(Intrinsics.from_fov(px, px, fov_deg), pose)


def test_flash_frame_plane_within_one_bin(mi):
    from simlunar.render.transient import TransientOptions, flash_frame

    cam = _nadir_camera(16, 4.0)  # narrow pixels: one range each
    bins = TimeBins.for_ranges(45.0, 60.0, 0.05)
    fr = flash_frame(_plane(), cam, bins=bins, options=TransientOptions(spp=16))
    assert fr.histograms.shape == (16, 16, bins.count * fr.oversample)
    # sum over bins = steady image (everything lands inside the window)
    assert fr.histograms.sum(-1) == pytest.approx(fr.steady, rel=1e-3)
    res = _read(fr.binned, bins)
    d = cam.directions_device(cam.pixel_centers().reshape(-1, 2)).reshape(16, 16, 3)
    truth = H * np.linalg.norm(d, axis=-1) / d[..., 2]
    assert res.valid.all()
    assert np.abs(res.range - truth).max() < bins.bin_range


def test_steered_beams_plane_within_one_bin(mi):
    from simlunar.render.transient import BeamCapture, capture_beams

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
    from simlunar.render.transient import BeamCapture, TransientOptions, capture_beams

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


def _sunny(mi):
    from simlunar.render.transient import TransientOptions, flash_frame

    sun = SunLight(elevation=np.radians(30.0), azimuth=np.radians(90.0), irradiance=1.0)
    bins = TimeBins.for_ranges(48.0, 56.0, 0.05)
    fr = flash_frame(
        _plane(), _nadir_camera(8, 3.0), bins=bins, options=TransientOptions(spp=16), sun=sun
    )
    return sun, bins, fr


def test_sun_background_per_bin_matches_the_steady_sun_image(mi):
    from simlunar.render.transient import BeamCapture

    sun, bins, fr = _sunny(mi)
    # a Lambertian plane of albedo 0.2 under the sun at 30 deg: L = 0.2 / pi * sin(30 deg)
    want = 0.2 / np.pi * 0.5
    assert fr.sun == pytest.approx(want, rel=1e-3)
    cap = BeamCapture(
        _plane(),
        [0.0, 0.0, H],
        footprint=FootprintOptions(1e-3, samples=4),
        window=bins,
        sun=sun,
        batch=8,
    )
    d = np.tile([[0.0, 0.0, -1.0]], (8, 1))
    assert cap.render_sun(d) == pytest.approx(want, rel=1e-3)
    # counts with the laser off: per-bin mean = sun radiance x scale x bin duration
    det = DetectorOptions(signal_photons=0.0, background_photons_per_s=2e9, pulses=500)
    lam = expected_counts(fr.binned, fr.sun, bins, det)
    counts = photon_counts(lam, options=det, rng=0)
    per_bin = fr.sun * 2e9 * bins.bin_s * det.pulses
    assert counts.mean(axis=-1) == pytest.approx(per_bin, rel=0.15)  # 160 bins each
    assert counts.mean() == pytest.approx(per_bin.mean(), rel=0.01)


def test_sun_adds_no_spurious_return(mi):
    _, bins, fr = _sunny(mi)
    # the sun never enters the transient film: the histograms hold the laser alone
    assert fr.histograms.sum(-1) == pytest.approx(fr.steady, rel=1e-3)
    det = DetectorOptions(signal_photons=2e6, background_photons_per_s=5e10, pulses=20)
    off = DetectorOptions(signal_photons=0.0, background_photons_per_s=5e10, pulses=20)
    no_laser = photon_counts(expected_counts(fr.binned, fr.sun, bins, off), options=off, rng=1)
    assert not extract_ranges(no_laser, bins, pulse=IMPULSE).valid.any()
    with_sun = photon_counts(expected_counts(fr.binned, fr.sun, bins, det), options=det, rng=2)
    dark = expected_counts(fr.binned, 0.0, bins, det) * det.pulses
    r_sun = extract_ranges(with_sun, bins, pulse=IMPULSE)
    r_dark = _read(dark, bins)
    assert r_sun.valid.all() and r_dark.valid.all()
    assert np.abs(r_sun.range - r_dark.range).max() < bins.bin_range


@pytest.mark.parametrize("bsdf_name", ["lambert", "oren_nayar", "hapke"])
def test_flash_steady_matches_the_ordinary_render_for_every_bsdf(mi, bsdf_name):
    # the flash's laser is the camera-centred point light of the ordinary renderer, so its
    # steady image must equal TerrainScene's with CameraLight: simlunar's Python BSDF plugins
    # work inside mitransient's transient_path
    from simlunar.render.lights import CameraLight
    from simlunar.render.materials import HapkeBSDF, LambertBSDF, OrenNayarBSDF
    from simlunar.render.scene import TerrainScene, luminance
    from simlunar.render.transient import TransientOptions, flash_frame

    bsdf = {"lambert": LambertBSDF(), "oren_nayar": OrenNayarBSDF(sigma=0.4), "hapke": HapkeBSDF()}[
        bsdf_name
    ]
    terrain, cam = _plane(slope=0.3), _nadir_camera(8, 20.0)
    bins = TimeBins.for_ranges(30.0, 70.0, 0.1)
    fr = flash_frame(terrain, cam, bins=bins, options=TransientOptions(spp=64), bsdf=bsdf)
    ref = luminance(
        TerrainScene(
            terrain, cam, lights=[CameraLight(1.0)], bsdf=bsdf, max_depth=2, spp=64
        ).render()
    )
    assert fr.steady.mean() == pytest.approx(ref.mean(), rel=0.01)
    assert fr.steady == pytest.approx(ref, rel=0.05)
    assert fr.histograms.sum(-1) == pytest.approx(fr.steady, rel=1e-3)


def test_batches_reuse_one_kernel(mi):
    import drjit as dr

    from simlunar.render.transient import BeamCapture

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


def test_photon_counts_are_poisson_with_the_rendered_mean(mi):
    # dispersion test on a rendered flash frame: every bin's draws have the rendered mean as
    # mean and variance; sum (x - m)^2 / m over draws and bins is chi^2 with that many dof
    from scipy import stats

    _, bins, fr = _sunny(mi)
    det = DetectorOptions(signal_photons=2e6, background_photons_per_s=5e10, pulses=1)
    lam = expected_counts(fr.binned, fr.sun, bins, det)
    assert lam.max() > 5 * lam.min() > 0  # returns above a sun floor
    draws = photon_counts(np.broadcast_to(lam, (40, *lam.shape)), options=det, rng=7)
    d = np.sum((draws - lam) ** 2 / lam)
    assert 0.001 < stats.chi2.sf(d, df=draws.size) < 0.999
    assert draws.mean(axis=0).sum() == pytest.approx(lam.sum(), rel=0.01)


def test_rendered_plane_keeps_the_sub_bin_range(mi):
    # beams at incidence angles that put a plane's range at 10 offsets across one 5 cm bin: the
    # noise-free reading of the rendered (tent-splatted, oversampled) return through a 1 ns pulse
    # is within 1 mm at every offset. A box-binned film snaps them to the bin centre
    # (+25 ... -19 mm: REFERENCES.md, "LIDAR physics, checked independently").
    from simlunar.lidar import shape_waveform
    from simlunar.render.transient import BeamCapture, capture_beams

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
