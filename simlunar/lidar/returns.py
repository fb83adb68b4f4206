"""What every LIDAR acquisition shares: the returns' options, reading counts and ranges, the scan.

- :class:`TransientOptions`: how the returns are rendered (read by :mod:`simlunar.render.transient`
  and :mod:`simlunar.render.beam_capture`; it lives here, beside the acquisitions' options that
  carry it, so that :mod:`simlunar.lidar` never imports :mod:`simlunar.render`).
- :class:`ReturnOptions`: pulse, detector, ranging, rendering, gate and instrument of every LIDAR
  (:class:`~simlunar.lidar.scan.SteeredBeamOptions`, :class:`~simlunar.lidar.flash.FlashOptions`).
- :func:`detect_counts`, :func:`read_ranges`: rendered impulse responses -> photon counts ->
  ranges (pulse and jitter, the sun's background and its shot noise, dead time, pile-up).
- :class:`LidarScan`: the ranges of one acquisition and its cost.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Camera
from simlunar.lidar.detector import (
    DetectorOptions,
    expected_counts,
    photon_counts,
    photon_counts_dead_time,
)
from simlunar.lidar.gate import GateOptions
from simlunar.lidar.hardware import LidarHardware
from simlunar.lidar.ranging import RangeOptions, extract_ranges
from simlunar.lidar.spad import spad_background, spad_correct
from simlunar.lidar.steering import ScanTiming
from simlunar.lidar.waveform import PulseOptions, TimeBins, shape_waveform
from simlunar.registry import Options, option

__all__ = [
    "LidarScan",
    "ReturnOptions",
    "TransientOptions",
    "detect_counts",
    "fired_energy_j",
    "read_ranges",
]


#: largest point-laser intensity (W/sr): a 10 kW-peak pulse in a 0.1 mrad beam is ~1e12 W/sr;
#: far above, the rendered film (float32) and the photon draws overflow
MAX_LASER_INTENSITY = 1e15


@dataclass(frozen=True)
class TransientOptions(Options):
    """Rendering of time-of-flight returns."""

    spp: int = option(
        64,
        doc="samples per pixel of a flash frame (steered beams use FootprintOptions.samples; "
        "at most 65536)",
        ge=1,
        le=65_536,
    )
    max_depth: int = option(
        2,
        doc="longest path (2 = direct only, the least that sees the laser; see "
        "simlunar.render.transient on steered beams)",
        ge=2,
        le=16,
    )
    seed: int = option(0, doc="sampler seed", ge=0)
    laser_intensity: float = option(
        1.0,
        doc="radiant intensity of the point laser; the histograms scale with it (at most "
        "1e15 W/sr, above the peak intensity of any pulsed laser: the film is float32)",
        unit="W/sr",
        key_unit="W/sr",
        gt=0,
        le=MAX_LASER_INTENSITY,
    )
    oversample: int = option(
        2,
        doc="rendered (fine) time bins per output bin. With the linear splat of the film, 2 "
        "keeps a plane's noise-free range within 0.01 mm at 0.65 pulse sigma per bin and 0.2 mm "
        "at 0.44 (tests/lidar/test_ranging.py); memory grows with it (at most 16)",
        ge=1,
        le=16,
    )


@dataclass(frozen=True)
class ReturnOptions(Options):
    """What every LIDAR here shares: rendering the returns and reading ranges from them."""

    pulse: PulseOptions = option(doc="pulse FWHM and timing jitter", default_factory=PulseOptions)
    detector: DetectorOptions = option(
        doc="photon scales, dark counts, dead time, pulses per reading",
        default_factory=DetectorOptions,
    )
    ranging: RangeOptions = option(
        doc="how a range is read from a histogram", default_factory=RangeOptions
    )
    transient: TransientOptions = option(
        doc="rendering (path depth, seed, laser intensity)", default_factory=TransientOptions
    )
    bin_range_m: float = option(0.05, doc="range width of a time bin", unit="m", gt=0)
    margin_m: float = option(
        2.0,
        doc="range margin on both sides of the predicted ranges in a receiver window (a "
        "flash: the reference plane's; a steered beam: each beam's, in its batch's window); it "
        "must cover the terrain's relief about the gate's reference plane",
        unit="m",
        ge=0,
    )
    hardware: LidarHardware | None = option(
        None,
        doc="the instrument: when given, the photon scales and dark counts of detector are "
        "derived from it (the lidar equation, simlunar.lidar.hardware) and the rendered laser "
        "intensity and sun irradiance; detector's own signal_photons and "
        "background_photons_per_s are then the expert override used only without it "
        "(simlunar.lidar.scan.with_hardware also sets the pulse, rates and divergence from it)",
    )
    gate: GateOptions = option(
        doc="the range gate: a reference plane (datum or altimeter reading) and the "
        "instrument's range limits (simlunar.lidar.gate)",
        default_factory=GateOptions,
    )

    def photon_detector(
        self, *, pulses=None, field_sr=None, lit_sr=None, sun_irradiance=1.0
    ) -> DetectorOptions:
        """The detector with the photon scales of :attr:`hardware` (or the expert override).

        ``field_sr`` / ``lit_sr``: a flash pixel's solid angle and the lit field (sr); None for
        a steered beam. ``pulses`` replaces the detector's pulses per reading.
        """
        det = self.detector
        if pulses is not None:
            det = dataclasses.replace(det, pulses=int(pulses))
        if self.hardware is None:
            return det
        hw = self.hardware.detector(
            field_sr=field_sr,
            lit_sr=lit_sr,
            laser_intensity=self.transient.laser_intensity,
            sun_irradiance=max(sun_irradiance, 1e-30),
        )
        return dataclasses.replace(
            det,
            signal_photons=hw.signal_photons,
            background_photons_per_s=hw.background_photons_per_s,
            dark_count_rate_hz=hw.dark_count_rate_hz,
        )


@dataclass(frozen=True, eq=False)
class LidarScan:
    """Ranges of one acquisition and its cost (arrays in the input order of the samples).

    Attributes
    ----------
    ranges : (n,) float64
        Slant range (m); NaN where invalid.
    valid : (n,) bool
    points : (n, 3) float64
        World points ``origin + range * direction`` (m); NaN where invalid.
    photons : (n,) float64
        Estimated signal photons of the reported return.
    order : (n,) int64
        Visiting order (indices into the samples); ``arange(n)`` for flash sensors.
    seconds : float
        Acquisition time (s).
    frames : int
        Pulses fired (steered beam) or flash frames.
    timing : ScanTiming or None
        Breakdown for steered beams.
    times : (n,) float64 or None
        When each sample was measured (s from the acquisition's start): a steered beam's
        first pulse at that pointing, a flash frame's start.
    returns : (n,) int64 or None
        Returns detected in each sample's histogram (the reported one is ``which``).
    energy_j : float
        Laser energy fired (J): every pulse at its energy, a gain control's probes included;
        0 where the options name no hardware (an expert override has no pulse energy).
    """

    ranges: np.ndarray
    valid: np.ndarray
    points: np.ndarray
    photons: np.ndarray
    order: np.ndarray
    seconds: float
    frames: int
    timing: ScanTiming | None = None
    times: np.ndarray | None = None
    returns: np.ndarray | None = None
    energy_j: float = 0.0

    def depth(self, camera: Camera) -> np.ndarray:
        """z-depth (m) of :attr:`points` along ``camera``'s optical axis (the guide view's
        depth convention of :class:`~simlunar.geometry.types.GroundTruth`); NaN where invalid."""
        return (self.points - camera.pose.position) @ camera.pose.forward


def fired_energy_j(options, pulses: float) -> float:
    """Laser energy (J) of ``pulses`` full-energy pulses of ``options``' hardware (0 without
    one: the expert photon scales name no pulse energy)."""
    hardware = getattr(options, "hardware", None)
    return 0.0 if hardware is None else float(pulses) * float(hardware.pulse_energy_j)


def read_ranges(counts, background, bins: TimeBins, pulse, det: DetectorOptions, ranging):
    """Ranges of photon ``counts`` (..., bins.count); a Geiger-mode receiver's (a SPAD's or a
    first-photon one's) detected returns refitted without pile-up
    (:func:`simlunar.lidar.spad.spad_correct`).

    Parameters
    ----------
    counts : (..., bins.count) array
        Photon counts (:func:`detect_counts`).
    background : float or (...) array
        The sun's steady luminance per reading (scaled by ``det.background_photons_per_s``);
        unused by the SPAD correction with ``ranging.spad_background = "histogram"``.
    bins : TimeBins
    pulse : PulseOptions
    det : DetectorOptions
    ranging : RangeOptions

    Returns
    -------
    RangeResult
        Ranges (m) from the window's start, photons, returns per reading.
    """
    res = extract_ranges(counts, bins, pulse=pulse, options=ranging, apd=det.apd,
                         pulses=det.pulses)  # fmt: skip
    # a first-photon receiver (infinite dead time) piles up as a SPAD does: corrected alike
    geiger = det.regime in ("spad", "first_photon")
    if not geiger or not ranging.pileup_correction or not res.valid.any():
        return res
    c = np.asarray(counts).reshape(-1, bins.count)
    ok = res.valid.reshape(-1)
    bg = np.broadcast_to(np.asarray(background, float), res.valid.shape).reshape(-1)
    per_bin = (bg * det.background_photons_per_s + det.dark_count_rate_hz) * bins.bin_s
    if ranging.spad_background == "histogram":  # the histogram's own, never the render's
        sigma = pulse.sigma_bins(bins)
        pos = (2.0 * res.range.reshape(-1)[ok] - bins.start_opl) / bins.bin_opl
        free = np.floor(pos - 4.0 * sigma - 1.0).clip(0).astype(int)
        per_bin = per_bin.copy()
        per_bin[ok] = spad_background(c[ok], bins, pulses=det.pulses,
                                      dead_time_s=det.dead_time_s, free_bins=free)  # fmt: skip
    fit = spad_correct(c[ok], bins, pulses=det.pulses, dead_time_s=det.dead_time_s,
                       sigma_bins=pulse.sigma_bins(bins), background=per_bin[ok])  # fmt: skip
    rng_m, ph = res.range.reshape(-1).copy(), res.photons.reshape(-1).copy()
    rng_m[ok], ph[ok] = fit.range, fit.photons * det.pulses
    keep = _spad_guards(fit, bins, ranging)
    valid = res.valid.reshape(-1).copy()
    gone = np.flatnonzero(ok)[~keep]
    valid[gone], rng_m[gone], ph[gone] = False, np.nan, 0.0
    return dataclasses.replace(res, range=rng_m.reshape(res.range.shape),
                               photons=ph.reshape(res.photons.shape),
                               valid=valid.reshape(res.valid.shape))  # fmt: skip


def _spad_guards(fit, bins: TimeBins, ranging) -> np.ndarray:
    """Which corrected returns the outlier guards keep (``ranging.spad_min_significance``,
    ``spad_max_sigma_m``)."""
    keep = np.ones(np.shape(fit.range), bool)
    if ranging.spad_min_significance > 0:
        keep &= fit.significance >= ranging.spad_min_significance
    if ranging.spad_max_sigma_m is not None:
        keep &= fit.position_sigma * bins.bin_range <= ranging.spad_max_sigma_m
    return keep


def detect_counts(
    hist, background, bins: TimeBins, pulse, detector: DetectorOptions, rng, oversample=1
):
    """Photon counts of rendered impulse responses: the pulse's shape, the expected counts of
    laser, sun and dark counts, then Poisson noise (with dead time where the detector has one).

    Parameters
    ----------
    hist : (..., bins.count * oversample) float
        Rendered returns per fine time bin.
    background : float or (...) array
        The sun's steady luminance per reading.
    bins : TimeBins
    pulse : PulseOptions
    detector : DetectorOptions
    rng : Generator
    oversample : int
        Fine bins per output bin of ``hist``.

    Returns
    -------
    (..., bins.count) array
        Photon counts per output bin.
    """
    shaped = shape_waveform(hist, bins, pulse, oversample=oversample)
    lam = expected_counts(shaped, background, bins, detector)
    if 0 < detector.dead_time_s < np.inf:
        return photon_counts_dead_time(lam, bins, options=detector, rng=rng)
    return photon_counts(lam, options=detector, rng=rng)
