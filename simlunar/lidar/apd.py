"""Linear-mode avalanche photodiode (APD) receivers: gain, excess noise, amplifier noise,
threshold.

A linear-mode APD (LOLA's Si APD, the InGaAs / HgCdTe arrays of flash LIDARs) turns each
photoelectron into an avalanche of mean gain ``M`` whose size fluctuates: the output of ``n``
photoelectrons has mean ``M n`` and variance ``F M^2 n`` with the excess noise factor (McIntyre
1966) ``F = k M + (1 - k) (2 - 1 / M)``, ``k`` the ratio of the hole and electron ionisation
coefficients (about 0.02 for Si, 0.4-0.5 for InGaAs). A transimpedance amplifier adds Gaussian
noise. Here the waveform is read in photoelectrons (output / M): each bin's primary count is
Poisson, each avalanche a Gamma variable of mean 1 and variance ``F - 1`` (so the sum of ``n``
is Gamma of shape ``n / (F - 1)``: mean ``n``, variance ``(F - 1) n`` on top of the Poisson
``n``, i.e. ``F n`` in all), plus the amplifier's noise. A return is detected where its
photoelectrons exceed the discriminator's ``threshold_pe`` (:attr:`ApdOptions.threshold_pe`,
used by the range extraction as its least signal) and the background's Gaussian noise
quantile.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.registry import Options, option

__all__ = [
    "MAX_COUNT",
    "POISSON_NORMAL_ABOVE",
    "ApdOptions",
    "agc_energy",
    "apd_waveform",
    "poisson_counts",
]


@dataclass(frozen=True)
class ApdOptions(Options):
    """A linear-mode APD receiver."""

    gain: float = option(100.0, doc="mean avalanche gain M", ge=1)
    ionisation_ratio: float = option(
        0.02,
        doc="k, the hole / electron ionisation ratio (Si about 0.02, InGaAs about 0.45)",
        ge=0,
        le=1,
    )
    amplifier_noise_pe: float = option(
        0.5,
        doc="RMS amplifier noise per bin and pulse referred to the input (the output noise in "
        "electrons divided by M)",
        unit="photoelectron",
        ge=0,
    )
    threshold_pe: float = option(
        5.0,
        doc="discriminator threshold: the least signal (summed over the pulses) of a detected "
        "return",
        unit="photoelectron",
        ge=0,
    )

    full_scale_pe: float | None = option(
        None,
        doc="the digitiser's full scale per pulse and bin, referred to the input: each pulse's "
        "waveform (signal, background and amplifier noise) clips there (the amplifier and "
        "digitiser saturate); None: no saturation (an ideal receiver)",
        unit="photoelectron",
        gt=0,
    )
    bits: int | None = option(
        None,
        doc="the digitiser's resolution: each pulse's waveform is rounded to full_scale_pe / "
        "2^bits steps (needs full_scale_pe); None: not quantised",
        ge=1,
        le=24,
    )

    agc_target: float | None = option(
        None,
        doc="automatic pulse-energy control (a flash frame): probe pulses set the frame's "
        "pulse energy so that its agc_quantile pixel's return peaks at this share of "
        "full_scale_pe (simlunar.lidar.apd.agc_energy); a background read and each probe "
        "cost a pulse slot; None: every pulse at full energy (needs full_scale_pe)",
        gt=0,
        le=1,
    )
    agc_probe_energy: float = option(
        1e-3,
        doc="the first probe pulse's energy as a share of the full pulse energy",
        gt=0,
        le=1,
    )
    agc_max_probes: int = option(
        4, doc="most probe pulses per frame (a saturated probe is followed by one 100x weaker)",
        ge=1, le=32,
    )  # fmt: skip
    agc_quantile: float = option(
        0.99,
        doc="which pixel's probe peak the gain control puts at agc_target: this quantile of "
        "the pixels' peaks, so the brightest (1 - agc_quantile) of them may clip; 1.0: the "
        "brightest pixel, which a single background photon through the APD's gain can be",
        gt=0,
        le=1,
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.bits is not None and self.full_scale_pe is None:
            raise ValueError("bits: a digitiser's resolution needs its full_scale_pe")
        if self.agc_target is not None and self.full_scale_pe is None:
            raise ValueError("agc_target: the gain control needs the digitiser's full_scale_pe")

    @property
    def excess_noise(self) -> float:
        """McIntyre's excess noise factor ``F = k M + (1 - k) (2 - 1 / M)``."""
        k, m = self.ionisation_ratio, self.gain
        return k * m + (1.0 - k) * (2.0 - 1.0 / m)


#: spreads of the background's peaks a gain control's probe peak must exceed to be a return
SIGNIFICANT = 8.0

#: mean above which a Poisson count is drawn from its normal limit (relative error of the
#: approximation below 1e-7; NumPy's Poisson sampler refuses means above ~9e18)
POISSON_NORMAL_ABOVE = 1e15
#: most detections one bin may report (an int64 holds 9.2e18): a count that large is a
#: detector saturated many orders of magnitude over, not a measurement
MAX_COUNT = 2**62


def poisson_counts(mean: np.ndarray, rng) -> np.ndarray:
    """Poisson draws of ``mean`` (int64): exact up to :data:`POISSON_NORMAL_ABOVE`, the normal
    limit ``mean + sqrt(mean) N(0, 1)`` above it, capped at :data:`MAX_COUNT`."""
    mean = np.asarray(mean, float)
    big = mean > POISSON_NORMAL_ABOVE
    if not big.any():
        return rng.poisson(mean)
    out = rng.poisson(np.where(big, 0.0, mean))
    m = mean[big]
    draw = np.rint(m + np.sqrt(m) * rng.standard_normal(m.shape))
    out[big] = np.minimum(draw, MAX_COUNT).astype(np.int64)
    return out


def apd_waveform(expected: np.ndarray, *, options: ApdOptions, pulses: int, rng=None):
    """Draw an APD's waveform, in photoelectrons, accumulated over ``pulses`` pulses.

    Parameters
    ----------
    expected : (..., count) float
        Mean photoelectrons per bin and pulse.
    options : ApdOptions
    pulses : int
    rng : seed or Generator

    Returns
    -------
    (..., count) float64
        Mean ``pulses x expected``, variance ``F x mean + pulses x amplifier_noise_pe^2``;
        with ``options.full_scale_pe`` the sum over the pulses of each pulse's waveform
        clipped at the full scale (and rounded to its ``bits``): at most ``pulses x
        full_scale_pe`` per bin.
    """
    rng = np.random.default_rng(rng)
    if options.full_scale_pe is not None:
        return _digitised(np.asarray(expected, float), options, int(pulses), rng)
    return _draw(np.asarray(expected, float), options, int(pulses), rng)


def agc_energy(probe: np.ndarray, background: np.ndarray, energy: float, *, options: ApdOptions):
    """The pulse energy (a share of the full energy) the gain control sets from one probe
    pulse's digitised waveforms ``probe`` (..., count) fired at ``energy``, and whether another
    probe must be fired first. ``background`` is the same receiver read for one pulse slot
    without firing (the sun and dark counts alone, same shape).

    Each pixel's peak is ``max - median`` of its waveform (the median is its background); the
    probe's peak ``P`` is the ``agc_quantile`` quantile of the pixels' peaks (the next higher
    pixel's: with fewer than ``1 / (1 - q)`` pixels, the brightest), the background's ``B``
    the same quantile of its pixels' peaks. The digitiser is linear below its full scale
    ``FS``, so the energy that puts ``P`` at ``agc_target x FS`` is ``energy x agc_target x FS
    / P`` (at most 1: a starved receiver gets the full energy). A probe in which more than
    ``1 - agc_quantile`` of the pixels reach ``FS`` only bounds ``P`` from below: the next
    probe is 100x weaker. A probe whose ``P - B`` is not significant saw no return: the next is
    100x stronger, and at the full energy the frame fires at it. Significant means over
    ``SIGNIFICANT`` times the spread of the background's pixel peaks (their median absolute
    deviation x 1.4826), and never less than one photoelectron's ``sqrt(F)`` (``F`` the APD's
    excess noise): under the sun, single background photons multiplied by the gain reach tens
    of pe somewhere in each pixel, so a probe's peaks are only a return where they stand out
    of the background's own.
    """
    w = np.asarray(probe, float)
    w = w.reshape(-1, w.shape[-1])
    fs, target = float(options.full_scale_pe), float(options.agc_target)
    q = float(options.agc_quantile)
    if (w >= fs).any(axis=-1).mean() > 1.0 - q:
        return energy / 100.0, True

    def peaks(x):
        x = np.asarray(x, float).reshape(-1, x.shape[-1])
        return x.max(axis=-1) - np.median(x, axis=-1)

    quiet = peaks(background)
    spread = 1.4826 * float(np.median(np.abs(quiet - np.median(quiet))))
    noise = max(spread, float(np.sqrt(options.excess_noise)))
    peak = float(np.quantile(peaks(w), q, method="higher"))
    if not peak - float(np.quantile(quiet, q, method="higher")) > SIGNIFICANT * noise:
        return min(energy * 100.0, 1.0), energy < 1.0
    return float(min(energy * target * fs / peak, 1.0)), False


def _digitised(expected: np.ndarray, options: ApdOptions, pulses: int, rng) -> np.ndarray:
    """The sum over ``pulses`` of each pulse's waveform clipped at the full scale and rounded
    to the digitiser's steps (each pulse drawn on its own: the clipping is per pulse)."""
    fs = float(options.full_scale_pe)
    step = None if options.bits is None else fs / 2 ** int(options.bits)
    out = np.zeros(expected.shape)
    for _ in range(pulses):
        w = np.minimum(_draw(expected, options, 1, rng), fs)
        if step is not None:
            w = np.round(w / step) * step
        out += w
    return out


def _draw(expected: np.ndarray, options: ApdOptions, pulses: int, rng) -> np.ndarray:
    """The unclipped waveform over ``pulses`` pulses (module docstring)."""
    lam = expected * pulses
    n = poisson_counts(lam, rng)
    f1 = options.excess_noise - 1.0
    out = n.astype(float)
    if f1 > 0:
        pos = n > 0
        out[pos] = rng.gamma(n[pos] / f1, f1)
    if options.amplifier_noise_pe > 0:
        out += rng.normal(0.0, options.amplifier_noise_pe * np.sqrt(pulses), out.shape)
    return out
