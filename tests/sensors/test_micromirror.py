"""The micromirror-steered flash through the Sensor protocol on a plane: depths at the
planned pixels, cost from its frames, and on a moving platform each frame from its own pose."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar import DetectorOptions, PulseOptions
from simlunar.terrain import Terrain

H = 50.0


def _plane() -> Terrain:
    return Terrain(heights=np.zeros((80, 80)), albedo=np.full((80, 80), 0.2, np.float32),
                   spacing=1.0, origin=(-40.0, 40.0))  # fmt: skip


def _camera(px: int, fov_deg: float) -> Camera:
    pose = Pose.look_at([0.0, 0.0, H], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    return Camera(Intrinsics.from_fov(px, px, fov_deg), pose)


def test_a_micromirror_needs_a_centred_guide_camera():
    from simlunar.sensors import LidarScene, MicromirrorFlash

    off = Camera(Intrinsics(fx=40.0, fy=40.0, cx=10.0, cy=16.0, width=32, height=32),
                 _camera(32, 6.0).pose)  # fmt: skip
    with pytest.raises(ValueError, match="centred principal point"):
        MicromirrorFlash(LidarScene(_plane(), off))


def test_scan_seconds_are_its_frames():
    # dots sharing a receiver pixel need frames of their own: 3 in receiver pixel (0, 0) of
    # an 8 x 8 receiver on a 32 x 32 guide -> 3 frames x 4 pulses / 20 Hz
    from simlunar.lidar.flash import FlashOptions
    from simlunar.sensors import LidarScene, MicromirrorFlash, MicromirrorOptions

    det = DetectorOptions(signal_photons=1.0, background_photons_per_s=0.0, pulses=4)
    opts = MicromirrorOptions(FlashOptions(detector=det, pulse_rate_hz=20.0), receiver_px=(8, 8))
    sensor = MicromirrorFlash(LidarScene(_plane(), _camera(32, 6.0)), opts)
    rc = np.array([[0, 0], [1, 2], [3, 3], [9, 20]])
    assert sensor.scan_seconds(rc) == pytest.approx(3 * 4 / 20.0)
    assert sensor.scan_seconds(np.zeros((0, 2), int)) == 0.0
    with pytest.raises(ValueError, match="rc is required"):
        sensor.acquire(None)


@pytest.mark.render
def test_scan_energy_is_its_frames_pulses_at_the_instrument_s_pulse_energy():
    # the same 3 frames x 4 pulses at the micromirror preset's 1 mJ: 12 mJ; with the expert
    # photon scales (no instrument) no pulse energy is known and a budget cannot be priced
    import dataclasses

    from simlunar.lidar.flash import FlashOptions
    from simlunar.lidar.hardware import INSTRUMENTS
    from simlunar.sensors import LidarScene, MicromirrorFlash, MicromirrorOptions

    hw = INSTRUMENTS["micromirror_flash"]
    det = DetectorOptions(pulses=4)
    flash = FlashOptions(detector=det, pulse_rate_hz=20.0)
    rc = np.array([[0, 0], [1, 1], [2, 2], [10, 10], [31, 31]])
    scene = LidarScene(_plane(), _camera(32, 6.0))
    with_hw = MicromirrorOptions(dataclasses.replace(flash, hardware=hw), receiver_px=(8, 8))
    assert MicromirrorFlash(scene, with_hw).scan_energy_j(rc) == pytest.approx(3 * 4 * 1e-3)
    assert MicromirrorFlash(scene, with_hw).scan_energy_j(np.zeros((0, 2), int)) == 0.0
    expert = MicromirrorFlash(scene, MicromirrorOptions(flash, receiver_px=(8, 8)))
    with pytest.raises(ValueError, match="an energy budget needs the micromirror_flash's pulse"):
        expert.scan_energy_j(rc)


def test_micromirror_flash_ranges_the_planned_pixels(mi):
    from simlunar.lidar.flash import FlashOptions
    from simlunar.render.transient import TransientOptions
    from simlunar.sensors import LidarScene, MicromirrorFlash, MicromirrorOptions

    det = DetectorOptions(signal_photons=2e6 * 16, background_photons_per_s=0.0, pulses=4)
    flash = FlashOptions(
        detector=det,
        pulse=PulseOptions(fwhm_s=1e-9),
        transient=TransientOptions(spp=256),
        pulse_rate_hz=20.0,
    )
    sensor = MicromirrorFlash(
        LidarScene(_plane(), _camera(32, 6.0)), MicromirrorOptions(flash, receiver_px=(8, 8))
    )
    rc = np.array([[3, 3], [2, 2], [9, 20], [30, 30], [27, 12]])  # two share receiver (0, 0)
    acq = sensor.acquire(rc, rng=0)
    assert acq.rc.tolist() == rc.tolist()
    assert acq.frames == 2 and acq.seconds == pytest.approx(2 * 4 / 20.0)
    assert acq.values == pytest.approx(H, abs=flash.bin_range_m)


@pytest.mark.render
def test_a_descending_micromirror_scores_its_dots_where_they_land(mi):
    # 10 m/s straight down with the exact pose: the dots of frame f (0.2 f s, from 50 - 2f m)
    # land on the plane along their planned rays, so the guide view (from 50 m, nadir,
    # principal point c = 16) sees them at z-depth 50 and at c + (uv - c)(50 - 2f) / 50
    # (closer to the nadir); a tolerance of 0.05 px covers a range bin's error across
    # (under 3 mm at 50 m, 0.02 px). The cost is the frames', as at rest
    from simlunar.lidar.flash import FlashOptions
    from simlunar.lidar.trajectory import Navigation, PlatformMotion
    from simlunar.render.transient import TransientOptions
    from simlunar.sensors import LidarScene, MicromirrorFlash, MicromirrorOptions

    det = DetectorOptions(signal_photons=2e6 * 16, background_photons_per_s=0.0, pulses=4)
    flash = FlashOptions(detector=det, pulse=PulseOptions(fwhm_s=1e-9),
                         transient=TransientOptions(spp=256), pulse_rate_hz=20.0)  # fmt: skip
    motion = PlatformMotion((0.0, 0.0, -10.0), navigation=Navigation("exact"))
    opts = MicromirrorOptions(flash, receiver_px=(8, 8), motion=motion)
    sensor = MicromirrorFlash(LidarScene(_plane(), _camera(32, 6.0)), opts)
    rc = np.array([[0, 0], [1, 2], [3, 3], [9, 20], [30, 30], [27, 12]])  # 3 share (0, 0)
    acq = sensor.acquire(rc, rng=0)
    assert acq.frames == 3 and acq.seconds == pytest.approx(3 * 4 / 20.0)
    assert acq.planned is None  # scored where the points project
    assert acq.values == pytest.approx(H, abs=flash.bin_range_m)
    shrink = (H - 2.0 * np.array([0, 1, 2, 0, 0, 0]))[:, None] / H
    want = 16.0 + (rc + 0.5 - 16.0) * shrink - 0.5
    assert acq.rc == pytest.approx(want, abs=0.05)
    assert np.abs(acq.rc[2] - rc[2]).min() > 0.9  # four metres lower: a pixel inwards


def test_micromirror_options_share_the_flash_sensors_receiver_and_its_check():
    from simlunar.sensors import FlashLidarOptions, MicromirrorOptions

    mm, fl = MicromirrorOptions(), FlashLidarOptions()
    assert (mm.flash, mm.receiver_px, mm.motion) == (fl.flash, fl.receiver_px, fl.motion)
    assert mm.receiver_px == (64, 64) and mm.motion is None
    with pytest.raises(ValueError, match=r"receiver_px must be each >= 1, got \(0, 8\)"):
        MicromirrorOptions(receiver_px=(0, 8))
