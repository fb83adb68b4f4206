"""Time bins of a return histogram and the laser pulse / detector timing response.

Mitsuba's transient film (mitransient) bins light by optical path length (OPL, metres) with a
box filter; the transport knows no pulse. So a rendered histogram is the scene's impulse
response, and the pulse shape and the detector's timing jitter are applied here afterwards,
as one Gaussian along the time axis (both are close to Gaussian for the diode-pumped
microchip lasers and SPAD / APD receivers flown on landers).

Range is half the round-trip OPL of a co-located emitter and receiver: ``R = OPL / 2``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.special import erf

__all__ = [
    "FWHM_PER_SIGMA",
    "SPEED_OF_LIGHT",
    "PulseOptions",
    "TimeBins",
    "pulse_kernel",
    "shape_waveform",
]

#: speed of light in vacuum (m/s)
SPEED_OF_LIGHT = 299_792_458.0

#: FWHM of a Gaussian in units of its standard deviation, 2 sqrt(2 ln 2)
FWHM_PER_SIGMA = 2.0 * np.sqrt(2.0 * np.log(2.0))


@dataclass(frozen=True)
class TimeBins:
    """Histogram bins in round-trip optical path length.

    Parameters
    ----------
    start_opl : float
        Round-trip OPL of the start of bin 0 (m).
    bin_opl : float
        Width of one bin in round-trip OPL (m); a range bin is half of it.
    count : int
        Number of bins.
    """

    start_opl: float
    bin_opl: float
    count: int

    def __post_init__(self) -> None:
        if not (np.isfinite(self.start_opl) and self.start_opl >= 0):
            raise ValueError(f"start_opl must be >= 0 m, got {self.start_opl}")
        if not self.bin_opl > 0:
            raise ValueError(f"bin_opl must be > 0 m, got {self.bin_opl}")
        if int(self.count) < 1:
            raise ValueError(f"count must be >= 1, got {self.count}")

    @classmethod
    def for_ranges(cls, near_m: float, far_m: float, bin_range_m: float) -> TimeBins:
        """Bins covering ranges ``[near_m, far_m]`` with range resolution ``bin_range_m`` (m)."""
        if not 0 <= near_m < far_m:
            raise ValueError(f"need 0 <= near_m < far_m, got {near_m}, {far_m}")
        n = int(np.ceil((far_m - near_m) / bin_range_m))
        return cls(start_opl=2.0 * near_m, bin_opl=2.0 * bin_range_m, count=n)

    @property
    def bin_s(self) -> float:
        """Bin duration (s)."""
        return self.bin_opl / SPEED_OF_LIGHT

    @property
    def bin_range(self) -> float:
        """Range width of one bin (m)."""
        return self.bin_opl / 2.0

    @property
    def centres_range(self) -> np.ndarray:
        """(count,) range of each bin centre (m)."""
        return (self.start_opl + (np.arange(self.count) + 0.5) * self.bin_opl) / 2.0

    def range_of(self, index) -> np.ndarray:
        """Range (m) of fractional bin index ``index`` (bin i spans [i, i + 1))."""
        return (self.start_opl + np.asarray(index, float) * self.bin_opl) / 2.0


@dataclass(frozen=True)
class PulseOptions:
    """Laser pulse and detector timing response (both Gaussian).

    Parameters
    ----------
    fwhm_s : float
        Full width at half maximum of the emitted pulse (s); 0 = an impulse.
    jitter_s : float
        RMS timing jitter of the detector and timing electronics (s).
    """

    fwhm_s: float = 2e-9
    jitter_s: float = 0.0

    def __post_init__(self) -> None:
        if not (self.fwhm_s >= 0 and self.jitter_s >= 0):
            raise ValueError(
                f"fwhm_s and jitter_s must be >= 0 s, got {self.fwhm_s}, {self.jitter_s}"
            )

    @property
    def sigma_s(self) -> float:
        """Standard deviation of the combined timing response (s)."""
        return float(np.hypot(self.fwhm_s / FWHM_PER_SIGMA, self.jitter_s))

    def sigma_bins(self, bins: TimeBins) -> float:
        """Standard deviation of the combined response in bins."""
        return self.sigma_s / bins.bin_s


def pulse_kernel(bins: TimeBins, pulse: PulseOptions) -> np.ndarray:
    """Unit-sum kernel (2 h + 1,) of the timing response, h = ceil(4 sigma) bins (at least 1)."""
    s = pulse.sigma_bins(bins)
    if s < 1e-3:
        return np.array([1.0])
    h = max(1, int(np.ceil(4.0 * s)))
    x = np.arange(-h, h + 1, dtype=float)
    # bin-integrated Gaussian: exact for a box-binned impulse response
    edges = (np.append(x - 0.5, h + 0.5)) / (np.sqrt(2.0) * s)
    k = np.diff(0.5 * erf(edges))
    return k / k.sum()


def shape_waveform(hist: np.ndarray, bins: TimeBins, pulse: PulseOptions) -> np.ndarray:
    """Convolve rendered impulse-response histograms with the pulse and detector response.

    Parameters
    ----------
    hist : (..., count) float
        Rendered return per bin (any unit; the transient film's radiance).
    bins : TimeBins
    pulse : PulseOptions

    Returns
    -------
    (..., count) float64
        Same unit; the sum over bins is kept except for light pushed past either end.
    """
    h = np.asarray(hist, float)
    if h.shape[-1] != bins.count:
        raise ValueError(f"hist has {h.shape[-1]} bins on its last axis, bins.count={bins.count}")
    k = pulse_kernel(bins, pulse)
    if k.size == 1:
        return h.copy()
    return ndimage.convolve1d(h, k, axis=-1, mode="constant", cval=0.0)
