"""Photon counting: expected counts per bin, shot noise, SPAD dead time and pile-up.

The renderer gives two noise-free images in radiance units: the laser's return per time bin
(``signal``, the transient film of a scene lit by the laser alone) and the sun's steady
radiance seen by the same receiver (``background``, an ordinary render; the sun is never a
transient emitter, whose light would land at a bogus path length). The sun is continuous, so
its expected photons per bin are its radiance times the bin duration; the laser's are its
binned return times the pulse's photon scale. Summed over ``pulses`` shots (a histogramming
receiver), the counts are Poisson with that mean without dead time; a linear-mode APD
(``DetectorOptions.apd``) adds its gain's excess noise and amplifier noise
(:mod:`simlunar.lidar.apd`).

A SPAD is blind for ``dead_time_s`` after each detection; with strong returns or sunlight
that distorts the histogram towards early bins (pile-up). ``dead_time_s = inf`` is the
classic one-detection-per-pulse (TCSPC) receiver, simulated exactly as a multinomial per
pulse; a finite dead time is simulated photon by photon in continuous time
(:mod:`simlunar.lidar.spad`, which also corrects the pile-up). The photon scales come from
the instrument's hardware (:mod:`simlunar.lidar.hardware`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.lidar.apd import ApdOptions, apd_waveform, poisson_counts
from simlunar.lidar.spad import spad_counts
from simlunar.lidar.waveform import TimeBins
from simlunar.registry import Options, option, shared_option

#: most dark counts per second a detector may be given, and (config) most photons per pulse and
#: unit radiance of an expert photon scale: the photon counts are Poisson draws, whose sampler
#: (NumPy) refuses a mean above ~1e18. Not a bound of the photon scales an instrument derives
#: (per unit of a rendered radiance, which is small: a LOLA-class beam's is ~1e13)
MAX_PHOTONS = 1e12

#: the detector options that :class:`DetectorOptions` and
#: :class:`~simlunar.lidar.hardware.LidarHardware` declare alike (the hardware's dark counts
#: become the detector's): name -> keywords of :func:`simlunar.registry.option`
DETECTOR_OPTIONS: dict[str, dict] = {
    "dark_count_rate_hz": dict(
        default=0.0,
        doc="dark (or noise-equivalent) counts per second, uniform in time",
        unit="1/s",
        ge=0,
        le=MAX_PHOTONS,
    ),
}


@dataclass(frozen=True)
class DetectorOptions(Options):
    """Receiver photon model."""

    signal_photons: float = option(
        100.0,
        doc="expected detected photons per pulse per unit of the rendered transient value "
        "(lumps pulse energy, receiver aperture, optics and quantum efficiency)",
        unit="photon",
        ge=0,
    )
    background_photons_per_s: float = option(
        1e9,
        doc="expected detected photons per second per unit of the rendered steady sun radiance "
        "(lumps aperture, field of view, filter bandwidth and efficiency)",
        unit="photon/s",
        ge=0,
    )
    dark_count_rate_hz: float = shared_option(DETECTOR_OPTIONS, "dark_count_rate_hz")
    pulses: int = option(1, doc="shots accumulated into one histogram (at most 1e6)", ge=1,
                         le=1_000_000)  # fmt: skip
    dead_time_s: float = option(
        0.0,
        doc="SPAD dead time, >= 0 (inf allowed): 0 = no dead time (photon counts, or an APD), "
        "inf = at most one detection per pulse, finite = a Geiger-mode SPAD with a "
        "non-paralysable dead time simulated in continuous time (simlunar.lidar.spad)",
        unit="s",
        key_unit="ns",
    )
    apd: ApdOptions | None = option(
        None,
        doc="a linear-mode APD (gain, excess noise, amplifier noise, threshold; "
        "simlunar.lidar.apd): the waveform in photoelectrons instead of photon counts",
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        # inf is a valid dead time (one detection per pulse), so it has no numeric bound
        if not self.dead_time_s >= 0:
            raise ValueError(f"dead_time_s must be >= 0 s, got {self.dead_time_s}")
        if self.apd is not None and self.dead_time_s != 0:
            raise ValueError(
                "apd: a linear-mode APD has no dead time (set dead_time_s = 0 or no apd)"
            )

    @property
    def regime(self) -> str:
        """``"photon_counting"``, ``"linear_apd"``, ``"first_photon"`` or ``"spad"``."""
        if self.apd is not None:
            return "linear_apd"
        if self.dead_time_s == 0:
            return "photon_counting"
        return "first_photon" if np.isinf(self.dead_time_s) else "spad"


def expected_counts(
    signal: np.ndarray,
    background: np.ndarray | float,
    bins: TimeBins,
    options: DetectorOptions,
) -> np.ndarray:
    """Expected detected photons per bin and per pulse.

    Parameters
    ----------
    signal : (..., count) float
        Laser return per bin (rendered transient value, already shaped by the pulse).
    background : (...) float or float
        Steady sun radiance seen by each receiver pixel / beam (rendered; 0 without sun).
    bins : TimeBins
    options : DetectorOptions

    Returns
    -------
    (..., count) float64
        Mean photons per bin for one pulse (>= 0).
    """
    s = np.asarray(signal, float)
    b = np.asarray(background, float)
    rate = b * options.background_photons_per_s + options.dark_count_rate_hz
    lam = s * options.signal_photons + (rate * bins.bin_s)[..., None]
    return np.maximum(lam, 0.0)


def photon_counts(expected: np.ndarray, *, options: DetectorOptions, rng=None) -> np.ndarray:
    """Draw a histogram of detections accumulated over ``options.pulses`` pulses.

    Parameters
    ----------
    expected : (..., count) float
        Mean photons per bin and pulse (:func:`expected_counts`).
    options : DetectorOptions
    rng : seed or Generator

    Returns
    -------
    (..., count) int64 (float64 photoelectrons for an APD)
        Detections per bin summed over the pulses.
    """
    rng = np.random.default_rng(rng)
    lam = np.asarray(expected, float)
    n = int(options.pulses)
    if options.apd is not None:
        return apd_waveform(lam, options=options.apd, pulses=n, rng=rng)
    if options.dead_time_s == 0:
        return poisson_counts(lam * n, rng)
    if np.isinf(options.dead_time_s):
        return _first_photon_counts(lam, n, rng)
    raise ValueError(
        "a finite dead time needs the bin width: call photon_counts_dead_time(expected, bins, "
        "options=..., rng=...)"
    )


def _first_photon_counts(lam: np.ndarray, n: int, rng) -> np.ndarray:
    """One detection at most per pulse: the first bin with a photon (exact, multinomial)."""
    cum = np.cumsum(lam, axis=-1)
    before = np.concatenate([np.zeros((*lam.shape[:-1], 1)), cum[..., :-1]], axis=-1)
    p = np.exp(-before) * -np.expm1(-lam)  # nothing before bin i, something in bin i
    p_none = np.exp(-cum[..., -1:])
    pv = np.concatenate([p, p_none], axis=-1)
    pv /= pv.sum(axis=-1, keepdims=True)
    flat = pv.reshape(-1, pv.shape[-1])
    out = rng.multinomial(n, flat)[:, :-1]
    return out.reshape(lam.shape).astype(np.int64)


def photon_counts_dead_time(
    expected: np.ndarray, bins: TimeBins, *, options: DetectorOptions, rng=None
) -> np.ndarray:
    """Detections with a non-paralysable dead time, simulated photon by photon.

    The detector is armed at the start of every pulse's window; each photon arrives at a
    continuous time inside its bin and a detection blinds the detector for exactly
    ``dead_time_s`` (:func:`simlunar.lidar.spad.spad_counts`; rounding the dead time to whole
    bins undercounted by 11-18 % at 1.5 ns). Shapes and units as :func:`photon_counts`.
    """
    lam = np.asarray(expected, float)
    if options.dead_time_s == 0 or np.isinf(options.dead_time_s):
        return photon_counts(lam, options=options, rng=rng)
    return spad_counts(
        lam, bins, dead_time_s=options.dead_time_s, pulses=int(options.pulses), rng=rng
    )


def coates_correction(counts: np.ndarray, pulses: int) -> np.ndarray:
    """Estimate the mean photons per bin and pulse from a one-detection-per-pulse histogram.

    Coates (1968): ``lambda_i = -ln(1 - h_i / (N - sum_{j < i} h_j))`` undoes pile-up when the
    dead time exceeds the window (``dead_time_s = inf``).

    Parameters
    ----------
    counts : (..., count) int
        Detections per bin over ``pulses`` pulses.
    pulses : int

    Returns
    -------
    (..., count) float64
        Estimated mean photons per bin and pulse (inf where every remaining pulse fired).
    """
    h = np.asarray(counts, float)
    before = np.cumsum(h, axis=-1) - h
    armed = pulses - before
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(armed > 0, h / armed, 0.0)
        return -np.log1p(-np.minimum(frac, 1.0))


#: Planck constant (J s)
PLANCK = 6.62607015e-34


__all__ = [
    "DETECTOR_OPTIONS",
    "PLANCK",
    "DetectorOptions",
    "coates_correction",
    "expected_counts",
    "photon_counts",
    "photon_counts_dead_time",
]
