"""Flash LIDAR acquisition on arrays (no rendering): the receiver's lattice and solid angles, the
range gate from the reference plane, frames of the micromirror flash, reading a frame."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar import DetectorOptions, PulseOptions, RangeOptions
from simlunar.lidar.flash import (
    FlashOptions,
    flash_window,
    micromirror_frames,
    micromirror_lit_sr,
    read_flash,
    receiver_rc,
    receiver_solid_angles,
)
from simlunar.lidar.gate import GateOptions
from simlunar.lidar.waveform import splat_paths

H = 50.0


def _nadir(px: int, fov_deg: float, height: float = H) -> Camera:
    pose = Pose.look_at([0.0, 0.0, height], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    return Camera(Intrinsics.from_fov(px, px, fov_deg), pose)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"bin_range_m": 0.0}, "bin_range_m must be > 0, got 0.0"),
        ({"margin_m": -1.0}, "margin_m must be >= 0, got -1.0"),
        ({"pulse_rate_hz": 0.0}, "pulse_rate_hz must be >= 0.001, got 0.0"),
    ],
)
def test_flash_options_refuse_bad_bins_margins_and_rates(kwargs, match):
    with pytest.raises(ValueError, match=match):
        FlashOptions(**kwargs)


def test_receiver_pixels_on_the_guide_lattice():
    # a 16 x 16 receiver on a 64 x 64 guide: receiver pixel (0, 0) has its centre at guide
    # (u, v) = (2, 2), index coordinates (1.5, 1.5); pixel (1, 1) (row-major index 17) at 5.5
    rc = receiver_rc((16, 16), (64, 64))
    assert rc.shape == (256, 2)
    assert rc[0] == pytest.approx([1.5, 1.5]) and rc[17] == pytest.approx([5.5, 5.5])
    assert rc[15] == pytest.approx([1.5, 61.5])  # (row 0, col 15)
    # a non-square receiver over a non-square guide scales each axis by itself
    assert receiver_rc((2, 4), (10, 40))[5] == pytest.approx([7.0, 14.5])


def test_receiver_solid_angles_tile_the_field():
    # the pixels of a pinhole receiver tile its rectangular field, whose solid angle is
    # 4 asin(sin(a) sin(b)) for half-angles a, b (a right rectangular pyramid)
    cam = _nadir(16, 30.0)
    omega = receiver_solid_angles(cam)
    assert omega.shape == (16, 16)
    a = b = np.radians(15.0)
    assert omega.sum() == pytest.approx(4 * np.arcsin(np.sin(a) * np.sin(b)), rel=1e-12)
    # symmetric about the axis, dimmest in the corners (about cos^3 off axis)
    assert omega == pytest.approx(omega[::-1, ::-1], rel=1e-12)
    assert omega[0, 0] < omega[7, 7]


def test_micromirror_lit_sr_is_the_field_on_a_plane_at_one_metre():
    # an 8 x 8 micromirror over 6 deg: fx = fy = 4 / tan(3 deg), lit W H / (fx fy)
    cam = _nadir(8, 6.0)
    assert micromirror_lit_sr(cam) == pytest.approx(64 * np.tan(np.radians(3.0)) ** 2 / 16)


def test_micromirror_frames_keep_receiver_pixels_apart():
    # receiver 8 x 8 on a 32 x 32 guide: 4 x 4 guide pixels per receiver pixel; the first two
    # dots share receiver pixel (0, 0), the last three are alone
    cam = _nadir(32, 6.0)
    uv = np.array([[3.5, 3.5], [2.5, 2.5], [20.5, 9.5], [30.5, 30.5], [12.5, 27.5]])
    assert list(micromirror_frames(uv, cam, (8, 8))) == [0, 1, 0, 0, 0]
    # three dots in one receiver pixel: frames 0, 1, 2 in their order
    assert list(micromirror_frames(np.array([[1.0, 1], [2, 2], [3, 3]]), cam, (8, 8))) == [0, 1, 2]


def test_flash_window_covers_the_plane_with_its_margins():
    # nadir receiver at 50 m over the datum z = 0: the pixel rays meet it between 50 m (the
    # centre) and 50 / cos(corner angle); the window adds margin_m on both sides
    cam = _nadir(8, 20.0)
    opts = FlashOptions(margin_m=1.0, bin_range_m=0.05)
    bins = flash_window(cam, options=opts)
    d = cam.rays(cam.pixel_centers().reshape(-1, 2))[1]
    r = H / -d[:, 2]
    assert bins.range_of(0) == pytest.approx(r.min() - 1.0)
    assert bins.range_of(bins.count) == pytest.approx(r.max() + 1.0, abs=0.05)
    assert bins.bin_range == pytest.approx(0.05)
    # a datum 10 m higher brings the window 10 m nearer
    up = flash_window(cam, options=FlashOptions(margin_m=1.0, gate=GateOptions(datum_z_m=10.0)))
    assert up.range_of(0) == pytest.approx(r.min() * 0.8 - 1.0)


def test_flash_window_refuses_the_altimeter_and_a_field_above_the_horizon():
    with pytest.raises(ValueError, match=r"gate\.altimeter"):
        flash_window(_nadir(8, 20.0), options=FlashOptions(gate=GateOptions(altimeter=True)))
    sky = Camera(Intrinsics.from_fov(8, 8, 20.0), Pose.look_at([0, 0, H], [0, 0, 2 * H]))
    with pytest.raises(ValueError, match="no receiver pixel meets the reference plane"):
        flash_window(sky, options=FlashOptions())


def test_read_flash_ranges_a_plane():
    # a 4 x 4 receiver over the plane z = 0 with its rendered returns at the true ranges
    # (tent-splatted on 2x finer bins, as the film does): the read ranges are the true ones
    # within a tenth of a bin, the points lie on the plane, one frame of pulses / rate seconds
    cam = _nadir(4, 20.0)
    det = DetectorOptions(signal_photons=200.0, background_photons_per_s=0.0, pulses=8)
    opts = FlashOptions(detector=det, pulse=PulseOptions(fwhm_s=1e-9), pulse_rate_hz=20.0)
    bins = flash_window(cam, options=opts)
    d = cam.rays(cam.pixel_centers())[1]
    truth = H / -d[..., 2]
    hist = splat_paths(2.0 * truth[..., None], 1.0, bins.refined(2)).reshape(4, 4, -1)
    frame = SimpleNamespace(
        histograms=hist.astype(np.float32), sun=None, bins=bins, oversample=2, sun_irradiance=1.0
    )
    scan = read_flash(frame, cam, options=opts, rng=0)
    assert scan.valid.all()
    assert scan.ranges == pytest.approx(truth, abs=0.1 * opts.bin_range_m)
    assert scan.points[..., 2] == pytest.approx(0.0, abs=0.1 * opts.bin_range_m)
    assert scan.seconds == pytest.approx(8 / 20.0) and scan.frames == 1
    assert np.array_equal(scan.order, np.arange(16).reshape(4, 4))
    # a fresh read of the same frame draws fresh photon noise
    again = read_flash(frame, cam, options=opts, rng=1)
    assert not np.array_equal(again.photons, scan.photons)


def _tilted_frame(cam, opts, *, z0: float, slope_deg: float):
    """A synthetic frame of the plane ``z = z0 + tan(slope) x`` through ``cam`` in the window
    ``flash_window`` gives, and the true ranges (paths outside the window are lost, as in the
    film)."""
    bins = flash_window(cam, options=opts)
    d = cam.rays(cam.pixel_centers())[1]
    truth = (H - z0) / (np.tan(np.radians(slope_deg)) * d[..., 0] - d[..., 2])
    hist = splat_paths(2.0 * truth[..., None], 1.0, bins.refined(2)).reshape(*cam.shape, -1)
    frame = SimpleNamespace(
        histograms=hist.astype(np.float32), sun=None, bins=bins, oversample=2, sun_irradiance=1.0
    )
    return frame, truth


@pytest.mark.parametrize("z0", [5.0, -5.0])
def test_a_datum_5m_off_under_a_15deg_slope_is_gated_by_the_prior_or_rejected(z0):
    # the navigation's datum is z = 0, the ground is a 15 deg slope 5 m above (or below) it,
    # seen from 50 m through a 32 x 32 receiver of 30 deg with 2 m margins and a 2 ns pulse
    cam = _nadir(32, 30.0)
    det = DetectorOptions(signal_photons=200.0, background_photons_per_s=0.0, pulses=8)

    def read(gate, edge_sigma):
        opts = FlashOptions(detector=det, pulse=PulseOptions(fwhm_s=2e-9), margin_m=2.0,
                            gate=gate, ranging=RangeOptions(edge_sigma=edge_sigma))  # fmt: skip
        frame, truth = _tilted_frame(cam, opts, z0=z0, slope_deg=15.0)
        scan = read_flash(frame, cam, options=opts, rng=0)
        return scan.valid, np.abs(scan.ranges - truth)

    # the datum taken as exact, every return kept: returns cut by the window's edge are
    # accepted 0.1 m and more off (the ideal gate's failure)
    valid, err = read(GateOptions(), 0.0)
    assert (err[valid] > 0.1).any()
    # the prior (the datum read with a 2 m error, slopes up to 20 deg) covers the ground: every
    # pixel measured, none more than 2 cm off
    prior = GateOptions(datum_sigma_m=2.0, max_slope_rad=np.radians(20.0))
    valid, err = read(prior, 0.0)
    assert valid.all() and err.max() < 0.02
    # an understated prior (0.5 m, no slope) with the edge guard: the cut returns are
    # rejected, what is kept is within 2 cm
    for gate in (GateOptions(), GateOptions(datum_sigma_m=0.5)):
        valid, err = read(gate, 3.0)
        assert valid.any() and not valid.all() and err[valid].max() < 0.02


def test_the_flash_gate_does_not_move_with_the_truth(monkeypatch):
    # the window a flash is rendered with comes from the pose and the datum as read: the
    # terrain moved 3 m up (its mean with it) leaves it where it was; the datum's error is
    # one draw from the render seed (the same window twice, another seed another window)
    from simlunar.render import flash_lidar
    from simlunar.terrain.types import Terrain

    seen = []

    def frame(terrain, camera, *, bins, **_):
        seen.append((float(terrain.heights.mean()), bins.start_opl, bins.count))
        raise StopIteration

    monkeypatch.setattr(flash_lidar, "flash_frame", frame)
    cam = _nadir(8, 20.0)
    flat = np.zeros((16, 16))
    opts = FlashOptions(gate=GateOptions(datum_sigma_m=1.0, max_slope_rad=np.radians(10.0)))
    for heights in (flat, flat + 3.0):
        t = Terrain(heights=heights, albedo=np.full((16, 16), 0.1, np.float32), spacing=1.0)
        with pytest.raises(StopIteration):
            flash_lidar.flash_scan(t, cam, options=opts)
    assert seen[0][0] != seen[1][0] and seen[0][1:] == seen[1][1:]
    other = dataclasses.replace(opts, transient=dataclasses.replace(opts.transient, seed=1))
    assert flash_window(cam, options=other).start_opl != seen[0][1]
    assert flash_window(cam, options=opts).start_opl == seen[0][1]


def test_micromirror_sampling_counts_render_samples_per_lit_guide_pixel():
    # hand case: a 384 x 384 guide over a 32 x 32 receiver: 144 guide pixels per receiver
    # pixel, so spp 128 gives a dot 128 / 144 = 0.89 samples (refused, naming 4 x 144 = 576);
    # a 96 x 96 receiver at spp 256: 256 / 16 = 16
    from simlunar.lidar.flash import MIN_SAMPLES_PER_DOT, micromirror_sampling

    assert micromirror_sampling((384, 384), (96, 96), 256) == pytest.approx(16.0)
    assert micromirror_sampling((384, 384), (32, 32), 576) == pytest.approx(MIN_SAMPLES_PER_DOT)
    with pytest.raises(ValueError, match=r"gives each lit guide pixel 0\.89 .* spp >= 576"):
        micromirror_sampling((384, 384), (32, 32), 128)
    with pytest.raises(ValueError, match="covers 144 of the 384 x 384"):
        micromirror_sampling((384, 384), (32, 32), 575)


def test_a_micromirror_sensor_refuses_dots_short_of_render_samples():
    from simlunar.lidar.flash import FlashOptions
    from simlunar.render.transient import TransientOptions
    from simlunar.sensors import LidarScene, MicromirrorFlash, MicromirrorOptions
    from simlunar.terrain import Terrain

    plane = Terrain(heights=np.zeros((8, 8)), albedo=np.full((8, 8), 0.2, np.float32),
                    spacing=1.0, origin=(-4.0, 4.0))  # fmt: skip
    cam = Camera(
        Intrinsics.from_fov(64, 64, 10.0),
        Pose.look_at([0, 0, 50.0], [0, 0, 0.0], up=(0.0, 1.0, 0.0)),
    )
    flash = FlashOptions(transient=TransientOptions(spp=63))
    with pytest.raises(ValueError, match="spp >= 64"):
        MicromirrorFlash(LidarScene(plane, cam), MicromirrorOptions(flash, receiver_px=(16, 16)))
    ok = dataclasses.replace(flash, transient=TransientOptions(spp=64))
    MicromirrorFlash(LidarScene(plane, cam), MicromirrorOptions(ok, receiver_px=(16, 16)))
