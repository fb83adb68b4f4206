"""Flash frames (mitransient): a plane at known range, the sun background, every BSDF, photon
statistics; steered beams: test_beam_capture.py."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import (
    DetectorOptions,
    FootprintOptions,
    TimeBins,
    expected_counts,
    extract_ranges,
    photon_counts,
)
from simlunar.render.lights import SunLight
from tests.render._transient_planes import IMPULSE, H, _nadir_camera, _plane, _read

pytestmark = pytest.mark.render


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


def _sunny(mi):
    from simlunar.render.transient import TransientOptions, flash_frame

    sun = SunLight(elevation=np.radians(30.0), azimuth=np.radians(90.0), irradiance=1.0)
    bins = TimeBins.for_ranges(48.0, 56.0, 0.05)
    fr = flash_frame(
        _plane(), _nadir_camera(8, 3.0), bins=bins, options=TransientOptions(spp=16), sun=sun
    )
    return sun, bins, fr


def test_sun_background_per_bin_matches_the_steady_sun_image(mi):
    from simlunar.render.beam_capture import BeamCapture

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
