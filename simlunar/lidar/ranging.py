"""Range extraction from photon-count histograms: peak or matched filter; first, last or
strongest return.

Per histogram the background level is the mean count away from the strongest return; the
matched filter correlates the counts with the pulse's timing response
(:func:`~simlunar.lidar.waveform.pulse_kernel`), which maximises the signal-to-noise ratio of
a known pulse shape in white (Poisson, background-dominated) noise. Returns are local maxima
of the filter output, at least one pulse width apart, whose counts in a window of about the
pulse's FWHM exceed the background's Poisson quantile of a one-sided ``threshold_sigma``
Gaussian tail, with an estimated signal of at least ``min_photons`` (counts within 4 sigma
of the pulse minus the background). The sub-bin position is the vertex of a parabola
through the peak bin and its neighbours, refined (``fit="ml"``, the default) by the
maximum-likelihood fit of the Poisson model ``lambda_i = A G_i(tau) + b`` (``G_i`` the pulse's
bin-integrated Gaussian, ``b`` the background estimate, ``A`` and ``tau`` free) in a window of
+-(3 sigma + 1) bins: Fisher scoring, which reaches the Cramer-Rao bound
(:func:`simlunar.lidar.bounds.range_crlb`) at high counts where the parabola's vertex is
biased by up to a few per cent of a bin by the sub-bin offset.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.special import erf

from simlunar.lidar.waveform import PulseOptions, TimeBins, pulse_kernel
from simlunar.registry import Options, option

__all__ = [
    "METHODS",
    "RETURNS",
    "RangeOptions",
    "RangeResult",
    "detection_probability",
    "extract_ranges",
    "pulses_for_detection",
]

METHODS = ("matched", "peak")
RETURNS = ("strongest", "first", "last")
FITS = ("ml", "parabola")


@dataclass(frozen=True)
class RangeOptions(Options):
    """How a range is read from a histogram."""

    method: str = option(
        "matched",
        doc="matched filter (correlate with the pulse response) or the raw histogram's peak",
        choices=METHODS,
    )
    which: str = option(
        "strongest", doc="which return to report when several are detected", choices=RETURNS
    )
    threshold_sigma: float = option(
        5.0,
        doc="detection threshold above the background, in standard deviations of its shot noise",
        ge=0,
    )
    min_photons: float = option(
        3.0, doc="smallest estimated signal of a return", unit="photon", ge=0
    )
    fit: str = option(
        "ml",
        doc="sub-bin position: maximum-likelihood fit of the pulse (Poisson model) or the "
        "parabola's vertex alone (also used where the pulse is narrower than 0.3 bin)",
        choices=FITS,
    )
    pileup_correction: bool = option(
        True,
        doc="with a Geiger-mode receiver (a SPAD, or first photon: infinite dead time), refit "
        "every detected return through the dead time's exact expected histogram (simlunar.lidar.spad.spad_correct): range and signal "
        "without the pile-up bias (a fit per return; the LIDAR scans apply it)",
    )
    spad_background: str = option(
        "given",
        doc="the background a SPAD's pile-up correction assumes: given (the caller's, e.g. the "
        "render's sun and the dark counts) or histogram (estimated from each histogram's "
        "signal-free leading bins, simlunar.lidar.spad.spad_background)",
        choices=("given", "histogram"),
    )
    spad_min_significance: float = option(
        0.0,
        doc="a Geiger-mode receiver's corrected return is kept only where its fit's likelihood "
        "ratio against the background alone (the dead time's own shape, simlunar.lidar.spad."
        "spad_correct) reaches this many sigmas; 0 = keep every detected return",
        ge=0,
        le=100,
    )
    spad_max_sigma_m: float | None = option(
        None,
        doc="a Geiger-mode receiver's corrected return is kept only where its fitted range's "
        "standard error (Fisher information at the fit) is at most this; None = no bound",
        unit="m",
        key_unit="mm",
        gt=0,
    )
    edge_sigma: float = option(
        0.0,
        doc="reject a return whose position lies within this many timing sigmas (at least one "
        "bin) of the window's first or last bin: the gate's edge cuts it and biases its "
        "position (a pulse centred outside the window reads at its edge); 0 = keep every "
        "return (the ideal window)",
        ge=0,
        le=100,
    )


@dataclass(frozen=True, eq=False)
class RangeResult:
    """Ranges read from histograms (arrays of the histograms' leading shape).

    Attributes
    ----------
    range : float64
        Range of the chosen return (m); NaN where invalid.
    valid : bool
        A return was detected.
    photons : float64
        Estimated signal photons of the chosen return (0 where invalid).
    returns : int64
        Number of returns detected.
    probe_pulses : int
        Pulses a gain control fired before the reading to set its energy (0 without one).
    energy_pulses : float or None
        The laser energy the reading fired, in full-energy pulses: a gain control's probes and
        the reading's own pulses each count their share of the full energy (None: the
        detector's pulses, all at the full energy).
    """

    range: np.ndarray
    valid: np.ndarray
    photons: np.ndarray
    returns: np.ndarray
    probe_pulses: int = 0
    energy_pulses: float | None = None


def _detection_threshold(mu, width: int, options: RangeOptions, apd, pulses: int):
    """Counts a window of ``width`` bins must exceed over its expected background ``mu``
    (Poisson quantile at ``threshold_sigma``, or the APD's Gaussian noise), and the least
    signal photons of a return."""
    # scipy.stats is imported where a threshold is set: it adds 0.45 s to every import of the
    # library (the LIDAR sensors are in the sensor registry that config reads)
    from scipy import stats

    min_photons = options.min_photons
    if apd is None:
        c_thr = stats.poisson.isf(stats.norm.sf(options.threshold_sigma), mu)
    else:
        # Gaussian: each bin's variance is F x its mean + the amplifier's, per pulse
        var = apd.excess_noise * mu + width * pulses * apd.amplifier_noise_pe**2
        c_thr = mu + options.threshold_sigma * np.sqrt(var)
        min_photons = max(min_photons, apd.threshold_pe)
    return c_thr, min_photons


def _reported_return(peak: np.ndarray, score: np.ndarray, which: str) -> np.ndarray:
    """Bin index of the reported return of each histogram (rows of ``peak``): the first, the
    last or the strongest detected peak."""
    if which == "first":
        return np.argmax(peak, axis=1)
    if which == "last":
        return peak.shape[1] - 1 - np.argmax(peak[:, ::-1], axis=1)
    return np.argmax(np.where(peak, score, -np.inf), axis=1)


def extract_ranges(
    counts: np.ndarray,
    bins: TimeBins,
    *,
    pulse: PulseOptions,
    options: RangeOptions = RangeOptions(),
    apd=None,
    pulses: int = 1,
) -> RangeResult:
    """Detect returns in histograms and report one range per histogram.

    Parameters
    ----------
    counts : (..., count) float or int
        Detections per bin (or expected counts, for a noise-free reading).
    bins : TimeBins
        The histograms' bins (round-trip OPL).
    pulse : PulseOptions
        Timing response used as the matched filter and for the return separation.
    options : RangeOptions
    apd : ApdOptions or None
        The counts are a linear-mode APD's waveform (photoelectrons): the detection test uses
        its Gaussian noise (variance ``F x mean + amplifier noise^2`` per bin) instead of the
        Poisson quantile, and its ``threshold_pe`` as the least signal.
    pulses : int
        Pulses accumulated in the counts (the APD's amplifier noise adds per pulse).

    Returns
    -------
    RangeResult
        Arrays of shape ``counts.shape[:-1]``.
    """
    c = np.asarray(counts, float)
    if c.shape[-1] != bins.count:
        raise ValueError(f"counts have {c.shape[-1]} bins, bins.count={bins.count}")
    lead = c.shape[:-1]
    c = c.reshape(-1, bins.count)
    k = pulse_kernel(bins, pulse)
    half = max(1, k.size // 2)
    bg = _background(c, half)
    score = ndimage.correlate1d(
        c, k if options.method == "matched" else [1.0], axis=1, mode="nearest"
    )
    # significance: photons in a window of about the pulse's FWHM against Poisson background
    m = max(1, int(np.ceil(1.5 * pulse.sigma_bins(bins))))
    win = ndimage.uniform_filter1d(c, 2 * m + 1, axis=1, mode="constant") * (2 * m + 1)
    mu = np.maximum(bg * (2 * m + 1), 1e-9)
    c_thr, min_photons = _detection_threshold(mu, 2 * m + 1, options, apd, pulses)
    full = ndimage.uniform_filter1d(c, 2 * half + 1, axis=1, mode="constant") * (2 * half + 1)
    photons = full - bg * (2 * half + 1)
    left = np.concatenate([np.full((len(c), 1), -np.inf), score[:, :-1]], axis=1)
    peak = score == ndimage.maximum_filter1d(score, 2 * half + 1, axis=1, mode="nearest")
    peak &= (score > left) & (win > c_thr) & (photons >= max(min_photons, 1e-12))
    n_ret = peak.sum(axis=1)
    valid = n_ret > 0
    idx = _reported_return(peak, score, options.which)
    pos = idx + 0.5 + _parabola_offset(score, idx)
    sig = pulse.sigma_bins(bins)
    if options.fit == "ml" and sig >= 0.3 and valid.any():
        pos[valid] = _ml_position(c[valid], pos[valid], bg[valid, 0], sig)
    if options.edge_sigma > 0:
        guard = max(options.edge_sigma * sig, 1.0)
        valid &= (pos >= guard) & (pos <= bins.count - guard)
    rng_m = bins.range_of(pos)
    rows = np.arange(len(idx))
    ph = np.where(valid, photons[rows, idx], 0.0)
    rng_m = np.where(valid, rng_m, np.nan)
    return RangeResult(
        range=rng_m.reshape(lead),
        valid=valid.reshape(lead),
        photons=ph.reshape(lead),
        returns=n_ret.astype(np.int64).reshape(lead),
    )


def _background(c: np.ndarray, half: int) -> np.ndarray:
    """Mean counts per bin (n, 1) outside +-3 half-widths of each histogram's strongest window."""
    win = ndimage.uniform_filter1d(c, 2 * half + 1, axis=1, mode="constant")
    top = np.argmax(win, axis=1)[:, None]
    keep = np.abs(np.arange(c.shape[1])[None, :] - top) > 3 * half
    n = np.maximum(keep.sum(axis=1, keepdims=True), 1)
    return np.where(keep, c, 0.0).sum(axis=1, keepdims=True) / n


def _parabola_offset(score: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Vertex offset in (-0.5, 0.5) bins of a parabola through bins idx - 1, idx, idx + 1."""
    n = score.shape[1]
    rows = np.arange(score.shape[0])
    lo = score[rows, np.clip(idx - 1, 0, n - 1)]
    mid = score[rows, idx]
    hi = score[rows, np.clip(idx + 1, 0, n - 1)]
    den = lo - 2.0 * mid + hi
    with np.errstate(divide="ignore", invalid="ignore"):
        off = np.where(den < 0, 0.5 * (lo - hi) / den, 0.0)
    return np.clip(np.nan_to_num(off), -0.5, 0.5)


def _ml_position(
    c: np.ndarray, pos0: np.ndarray, bg: np.ndarray, sigma: float, iterations: int = 12
) -> np.ndarray:
    """Maximum-likelihood return position (bins from the window start) by Fisher scoring.

    Model of the counts near the return: ``lambda_i = A G_i(tau) + b``, with
    ``G_i(tau) = Phi((i + 1 - tau) / sigma) - Phi((i - tau) / sigma)`` the pulse integrated
    over bin i, ``b`` fixed at the background estimate, ``A`` and ``tau`` fitted in a window
    of +-(3 sigma + 1) bins around the initial position ``pos0``. Where the fit fails (non-
    finite, or it moved more than 2 bins) the initial position is kept.

    Parameters
    ----------
    c : (n, count) float
        Counts.
    pos0 : (n,) float
        Initial positions (bins), e.g. the parabola's vertex.
    bg : (n,) float
        Background counts per bin.
    sigma : float
        Timing response's standard deviation (bins).

    Returns
    -------
    (n,) float64
    """
    count = c.shape[1]
    w = int(np.ceil(3.0 * sigma)) + 1
    rel = np.arange(-w, w + 1)
    idx = np.floor(pos0).astype(np.int64)[:, None] + rel[None, :]
    inside = (idx >= 0) & (idx < count)
    cw = np.where(inside, np.take_along_axis(c, np.clip(idx, 0, count - 1), axis=1), 0.0)
    b = np.maximum(bg, 0.0)[:, None]
    lo = idx.astype(float)
    tau = pos0.astype(float).copy()
    amp = np.maximum(cw.sum(axis=1) - b[:, 0] * inside.sum(axis=1), 1.0)
    root2 = np.sqrt(2.0)
    for _ in range(iterations):
        z0 = (lo - tau[:, None]) / sigma
        z1 = z0 + 1.0 / sigma
        g = 0.5 * (erf(z1 / root2) - erf(z0 / root2))
        dg = (np.exp(-0.5 * z0**2) - np.exp(-0.5 * z1**2)) / (np.sqrt(2 * np.pi) * sigma)
        lam = np.maximum(amp[:, None] * g + b, 1e-12)
        r = np.where(inside, (cw - lam) / lam, 0.0)
        ja, jt = g, amp[:, None] * dg  # d lambda / d A, d lambda / d tau
        q = np.where(inside, 1.0 / lam, 0.0)
        faa, fat, ftt = (q * ja * ja).sum(1), (q * ja * jt).sum(1), (q * jt * jt).sum(1)
        ga, gt = (r * ja).sum(1), (r * jt).sum(1)
        det = faa * ftt - fat**2
        with np.errstate(divide="ignore", invalid="ignore"):
            d_amp = (ftt * ga - fat * gt) / det
            d_tau = (faa * gt - fat * ga) / det
        ok = np.isfinite(d_amp) & np.isfinite(d_tau)
        tau = np.where(ok, tau + np.clip(d_tau, -0.5, 0.5), tau)
        amp = np.where(ok, np.maximum(amp + d_amp, 0.5 * amp), amp)
    bad = ~np.isfinite(tau) | (np.abs(tau - pos0) > 2.0)
    return np.where(bad, pos0, tau)


def detection_probability(signal_photons, background_per_bin: float, pulses, *, bins: TimeBins,
                          pulse: PulseOptions, options: RangeOptions = RangeOptions()):  # fmt: skip
    """Probability that a photon-counting histogram of ``pulses`` pulses holds a detected
    return (:func:`extract_ranges`' test), in closed form.

    The test counts the photons in a window of ``2 m + 1`` bins about the return (``m =
    ceil(1.5 sigma)`` bins) against the Poisson quantile ``c`` of its background at
    ``threshold_sigma``: ``P = P(Poisson(n (f S + w b)) > c(n w b))`` with ``S`` the signal
    photons per pulse, ``f`` the pulse's share inside the window (averaged over the return's
    position in the window's central bin), ``b`` the background photons per bin and pulse and ``w`` the window's
    bins; the return's signal must also reach ``min_photons`` (its expectation ``n S`` is
    compared). The background is taken as known (the reading estimates it from the histogram).

    Returns
    -------
    float64 array of the broadcast shape of ``signal_photons`` and ``pulses``
    """
    from scipy import stats

    s = np.asarray(signal_photons, float)
    n = np.asarray(pulses, float)
    sig = pulse.sigma_bins(bins)
    m = max(1, int(np.ceil(1.5 * sig)))
    w = 2 * m + 1
    # the return's centre anywhere in the window's central bin: the share averaged over it
    u = np.linspace(-0.5, 0.5, 21)
    root = max(sig, 1e-9) * np.sqrt(2.0)
    f = float(np.mean(0.5 * (erf((m + 0.5 - u) / root) - erf((-m - 0.5 - u) / root))))
    mu_bg = np.maximum(n * w * background_per_bin, 1e-9)
    c_thr = stats.poisson.isf(stats.norm.sf(options.threshold_sigma), mu_bg)
    p = stats.poisson.sf(c_thr, n * (f * s) + mu_bg)
    return np.where(n * s >= options.min_photons, p, 0.0)


def pulses_for_detection(signal_photons: float, background_per_bin: float, *, target: float,
                         bins: TimeBins, pulse: PulseOptions,
                         options: RangeOptions = RangeOptions(),
                         max_pulses: int = 1_000_000) -> int:  # fmt: skip
    """The fewest pulses per point whose histogram detects a return of ``signal_photons`` per
    pulse with probability at least ``target`` (:func:`detection_probability`); a
    ``ValueError`` when even ``max_pulses`` do not.
    """
    if not 0 < target < 1:
        raise ValueError(f"target must be in (0, 1), got {target}")

    def ok(n: int) -> bool:
        return bool(detection_probability(signal_photons, background_per_bin, n, bins=bins,
                                          pulse=pulse, options=options) >= target)  # fmt: skip

    if not ok(max_pulses):
        raise ValueError(
            f"{signal_photons:g} photons per pulse are not detected with probability {target} "
            f"within {max_pulses} pulses"
        )
    hi = 1
    while not ok(hi):
        hi *= 2
    lo = hi // 2  # ok(hi), not ok(lo) (or lo = 0)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    return hi
