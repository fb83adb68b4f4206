"""The micromirror-steered flash LIDAR: the paper's envisioned image-directed range sensor.

A micromirror projector at the guide camera lights only the planned pixels; a low-resolution
receiver times their returns (dots sharing a receiver pixel go to different frames,
:func:`~simlunar.lidar.flash.micromirror_frames`), rendered by
:func:`~simlunar.render.flash_lidar.micromirror_flash`. On a moving platform
(``MicromirrorOptions.motion``) each frame is rendered from the pose at its time and its dots
are scored where their points project in the guide view; the rounds of a multi-round plan
continue the trajectory (:class:`~simlunar.sensors.rounds.PlatformRounds`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.lidar.flash import FlashOptions, micromirror_frames, micromirror_sampling
from simlunar.lidar.returns import fired_energy_j
from simlunar.lidar.trajectory import Flight, PlatformMotion
from simlunar.registry import Options, shared_option
from simlunar.render.flash_lidar import micromirror_flash
from simlunar.sensors.base import Acquisition
from simlunar.sensors.lidar import (
    FLASH_SENSOR_OPTIONS,
    LidarScene,
    _need_hardware,
    _to_guide,
    check_receiver_px,
)
from simlunar.sensors.rounds import PlatformRounds, platform_trajectory

__all__ = ["MicromirrorFlash", "MicromirrorOptions"]


@dataclass(frozen=True)
class MicromirrorOptions(Options):
    """Options of :class:`MicromirrorFlash`.

    Its flash's ``transient.spp`` needs about ``(guide pixels / receiver pixels) x 16`` for a
    clean return (docs/lidar.md); fewer than 4 render samples per lit guide pixel are refused
    when the sensor is built (:func:`~simlunar.lidar.flash.micromirror_sampling`). On a moving
    platform (``motion``) frame ``f`` is rendered from the pose at ``f`` x pulses / pulse rate
    (:func:`~simlunar.render.flash_lidar.micromirror_flash`); the mirrors stay the planned
    pixels (``motion.retarget`` is the steered beam's).
    """

    flash: FlashOptions = shared_option(FLASH_SENSOR_OPTIONS, "flash")
    receiver_px: tuple[int, int] = shared_option(FLASH_SENSOR_OPTIONS, "receiver_px")
    motion: PlatformMotion | None = shared_option(FLASH_SENSOR_OPTIONS, "motion")

    def __post_init__(self):
        super().__post_init__()
        check_receiver_px(self.receiver_px)


class MicromirrorFlash:
    """The paper's envisioned sensor: a micromirror array at the guide camera lights only the
    planned pixels; a low-resolution receiver times their returns.

    Parameters
    ----------
    scene : LidarScene
        Its guide camera needs a centred principal point (the projector emitter).
    options : MicromirrorOptions, optional
    """

    name = "micromirror_flash"
    needs_plan = True

    def __init__(self, scene: LidarScene, options: MicromirrorOptions | None = None) -> None:
        if not scene.camera.intrinsics.is_centred:
            raise ValueError(
                "a micromirror flash needs a guide camera with a centred principal point"
            )
        self.scene = scene
        self.options = options or MicromirrorOptions()
        o = self.options
        micromirror_sampling(scene.camera.shape, o.receiver_px, o.flash.transient.spp)

    def acquire(self, rc: np.ndarray | None, *, rng=None) -> Acquisition:
        """Light and time the planned guide pixels ``rc`` ((k, 2) int (row, col)); ``rng``:
        photon noise (and, moving, the jitter's phases and the navigation errors)."""
        if rc is None:
            raise ValueError("a micromirror flash lights planned pixels: rc is required")
        if self.options.motion is not None:
            g = np.random.default_rng(rng)
            return self._moving(rc, g, self.trajectory(g), 0.0)
        scan = self._scan(rc, rng)
        return _to_guide(scan, self.scene.camera, rc)

    def _scan(self, rc, rng, flight: Flight | None = None):
        """The rendered scan of planned guide pixels ``rc`` (at rest without a ``flight``)."""
        s, o = self.scene, self.options
        uv = np.asarray(rc, float)[:, ::-1] + 0.5
        return micromirror_flash(s.terrain, s.camera, uv, options=o.flash,
                                 receiver_shape=tuple(o.receiver_px), rng=rng,
                                 scene={"sun": s.sun, "bsdf": s.bsdf}, flight=flight)  # fmt: skip

    def trajectory(self, rng):
        """The platform's trajectory from the guide camera's centre at t = 0 (its jitter
        phases drawn from ``rng``, a Generator); None at rest."""
        return platform_trajectory(self.scene.camera, self.options.motion, rng)

    def _moving(self, rc, rng, trajectory, start_s: float) -> Acquisition:
        """The acquisition of ``rc`` on ``trajectory``, its first frame at ``start_s`` (s on
        it)."""
        flight = Flight(trajectory, self.options.motion.navigation, start_s)
        scan = self._scan(rc, rng, flight)
        # a moving platform's dots land off the planned pixels' points: scored where their
        # points project, as a moving steered beam's
        return _to_guide(scan, self.scene.camera, None)

    def rounds(self, *, rng=None) -> PlatformRounds:
        """The rounds of one multi-round acquisition, measured one after the other
        (:class:`~simlunar.sensors.rounds.PlatformRounds`: on a moving platform each round's
        first frame fires when the previous round's last ended; the mirrors switch at once)."""
        return PlatformRounds(self, rng)

    def _frames(self, rc: np.ndarray) -> int:
        """Frames that light guide pixels ``rc`` (k, 2): the most dots sharing a receiver
        pixel (:func:`~simlunar.lidar.flash.micromirror_frames`); 0 for none."""
        if len(rc) == 0:
            return 0
        uv = np.asarray(rc, float)[:, ::-1] + 0.5
        return int(micromirror_frames(uv, self.scene.camera, self.options.receiver_px).max()) + 1

    def scan_seconds(self, rc: np.ndarray) -> float:
        """Modelled time (s) of lighting guide pixels ``rc`` (k, 2): frames (the most dots
        sharing a receiver pixel) x pulses / rate; no render (what a planner may ask)."""
        f = self.options.flash
        return self._frames(rc) * f.detector.pulses / f.pulse_rate_hz

    def scan_energy_j(self, rc: np.ndarray) -> float:
        """Modelled laser energy (J) of lighting guide pixels ``rc`` (k, 2): the frames x
        pulses x the hardware's pulse energy (each frame's pulses spread over its dots)."""
        f = self.options.flash
        _need_hardware(f, self.name)
        return fired_energy_j(f, self._frames(rc) * f.detector.pulses)
