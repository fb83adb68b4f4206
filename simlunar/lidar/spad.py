"""Geiger-mode SPAD receivers: dead time in continuous time, pile-up and its correction.

A SPAD fires on the first photon it sees and is then blind for a dead time ``tau_d``
(non-paralysable: photons arriving while blind neither count nor extend it). With strong
returns or sunlight, early photons blind the detector for later ones: the histogram piles up
towards early times (a range bias) and undercounts. Rounding the dead time to whole bins
undercounts by 11-18 % at 1.5 ns (docs/lidar.md, "How a return is made", step 4), so:

- :func:`spad_counts` simulates every photon in continuous time (the event-level simulation):
  per pulse, Poisson arrivals from the piecewise-constant rate of each bin, uniform inside
  the bin; the detector is armed at the start of every pulse's window.
- :func:`spad_expected` is the exact expected histogram on sub-steps of ``1 / substeps`` bin:
  the probability of being armed at sub-step k is ``1 - sum of the detection probabilities of
  the last D sub-steps`` (two detections closer than the dead time are impossible), and a
  detection there has probability ``armed x (1 - exp(-rate))``.
- :func:`spad_correct` undoes pile-up. Coates' correction (infinite dead time) diverges once
  the detector is nearly never armed at the return's peak (>= about 10 photons per pulse):
  there the histogram holds no information on those bins. So the return is fitted as a
  parametric pulse (amplitude, position; background per bin known) by maximising the Poisson
  likelihood of the measured histogram under :func:`spad_expected` (Gauss-Newton), which uses
  the leading edge and the re-armed tail; the fitted amplitude is the corrected signal.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from scipy import ndimage
from scipy.special import erf

from simlunar.lidar.waveform import TimeBins

__all__ = ["SpadFit", "spad_background", "spad_correct", "spad_counts", "spad_expected"]


#: mean photons per pulse above which a histogram is simulated detection by detection
#: (:func:`_simulate_detections`, cost linear in the detections, at most one per dead time)
#: instead of photon by photon (cost linear in the photons: a pulse of 1e12 photons, the
#: schema's cap, would never end). Below it the photon-level draws are kept as they were.
PHOTON_LEVEL_MAX = 1e4


# not cached on disk: numba's np.random in a cached function read wrong draws (a third of the
# counts) in a process that had run another numba function first (the Lloyd planner), when the
# cache was written by a process that had not (tests/lidar/test_spad.py after
# tests/config/test_planners.py); compiling it costs about a second
@numba.njit(cache=False, nogil=True)
def _simulate(lam, pulses, dead_bins, seed, photon_level_max):  # pragma: no cover - compiled
    np.random.seed(seed)  # noqa: NPY002 - numba supports the legacy generator only
    n, m = lam.shape
    out = np.zeros((n, m), np.int64)
    cum = np.zeros(m + 1)
    for h in range(n):
        cum[0] = 0.0
        for i in range(m):
            cum[i + 1] = cum[i] + lam[h, i]
        total = cum[m]
        if total <= 0.0:
            continue
        if total > photon_level_max:
            _simulate_detections(lam[h], pulses, dead_bins, out[h])
            continue
        for _ in range(pulses):
            k = np.random.poisson(total)  # noqa: NPY002
            if k == 0:
                continue
            # arrival times: inverse CDF of the piecewise-constant rate (bins, continuous)
            u = np.sort(np.random.random(k)) * total  # noqa: NPY002
            blind_until = -1.0
            j = 0
            for q in range(k):
                while cum[j + 1] < u[q]:
                    j += 1
                t = j + (u[q] - cum[j]) / lam[h, j]
                if t >= blind_until:
                    out[h, j] += 1
                    blind_until = t + dead_bins
    return out


@numba.njit(cache=False, nogil=True)  # np.random inside: not cached on disk, as _simulate
def _simulate_detections(lam, pulses, dead_bins, out):  # pragma: no cover - compiled
    """The same process as the photon-level loop, drawn detection by detection: the arrivals
    are a Poisson process (memoryless), so the first arrival after the detector re-arms at
    ``t`` comes after an Exp(1) amount of integrated rate, and the photons of a blind interval
    need not be drawn at all."""
    m = lam.shape[0]
    for _ in range(pulses):
        t = 0.0
        j = 0
        while j < m:
            e = -np.log(1.0 - np.random.random())  # noqa: NPY002
            while j < m:
                seg = (j + 1 - t) * lam[j]
                if seg >= e and lam[j] > 0.0:
                    break
                e -= seg
                j += 1
                t = float(j)
            if j >= m:
                break
            t += e / lam[j]
            out[j] += 1
            t += dead_bins
            j = int(t)


def spad_counts(
    expected: np.ndarray,
    bins: TimeBins,
    *,
    dead_time_s: float,
    pulses: int,
    rng=None,
    photon_level_max: float = PHOTON_LEVEL_MAX,
) -> np.ndarray:
    """Event-level simulation of a SPAD histogram (continuous-time dead time).

    Parameters
    ----------
    expected : (..., count) float
        Mean photons per bin and pulse (signal + background + dark counts, before the SPAD).
    bins : TimeBins
    dead_time_s : float
        Non-paralysable dead time (s), > 0 (``inf``: one detection per pulse).
    pulses : int
        Pulses accumulated.
    rng : seed or Generator
    photon_level_max : float
        Mean photons per pulse (a histogram's window) above which the detections are drawn
        one by one (the same process; cost linear in the detections, not the photons).

    Returns
    -------
    (..., count) int64
        Detections per bin over the pulses.
    """
    lam = np.ascontiguousarray(np.asarray(expected, float).reshape(-1, bins.count))
    if not dead_time_s > 0:
        raise ValueError(f"dead_time_s must be > 0, got {dead_time_s}")
    if np.any(lam < 0):
        raise ValueError("expected counts must be >= 0")
    seed = int(np.random.default_rng(rng).integers(0, 2**31 - 1))
    dead = min(dead_time_s / bins.bin_s, 4.0 * bins.count)
    out = _simulate(lam, int(pulses), float(dead), seed, float(photon_level_max))
    return out.reshape(np.shape(expected))


def spad_expected(
    expected: np.ndarray, bins: TimeBins, *, dead_time_s: float, substeps: int = 16
) -> np.ndarray:
    """Expected SPAD detections per bin and pulse (pile-up included).

    Parameters
    ----------
    expected : (..., count) float
        Mean photons per bin and pulse arriving at the detector.
    bins : TimeBins
    dead_time_s : float
        Non-paralysable dead time (s), > 0.
    substeps : int
        Sub-steps per bin (the dead time is resolved to ``1 / substeps`` bin).

    Returns
    -------
    (..., count) float64
        Probability of a detection in each bin per pulse.
    """
    lam = np.asarray(expected, float)
    shape = lam.shape
    lam = np.ascontiguousarray(lam.reshape(-1, bins.count))
    s = int(substeps)
    d = max(1, round(min(dead_time_s / bins.bin_s, 4.0 * bins.count) * s))
    return _expected(lam, s, d).reshape(shape)


@numba.njit(cache=True, nogil=True)
def _expected(lam, s, d):  # pragma: no cover - compiled
    n, m = lam.shape
    out = np.zeros((n, m))
    p = np.zeros(m * s)
    for h in range(n):
        window = 0.0  # detection probability of the last d sub-steps
        for i in range(m * s):
            armed = max(1.0 - window, 0.0)
            p[i] = armed * -np.expm1(-lam[h, i // s] / s)
            out[h, i // s] += p[i]
            window += p[i]  # a detection at sub-step i blinds sub-steps i + 1 ... i + d
            if i - d >= 0:
                window -= p[i - d]
    return out


@dataclass(frozen=True, eq=False)
class SpadFit:
    """A pile-up-corrected return (arrays over the histograms).

    Attributes
    ----------
    photons : float64
        Corrected signal photons per pulse (the fitted amplitude).
    position : float64
        Fitted return position (fractional bin index from the window's start).
    range : float64
        The position as a range (m).
    significance : float64
        ``sqrt(2 (ll - ll_0))``: the likelihood ratio of the fitted return against the
        background alone (the same dead time, no pulse), in Gaussian sigmas (Wilks).
    position_sigma : float64
        The fitted position's standard error (bins), from the Fisher information of
        (log amplitude, position) at the fit.
    """

    photons: np.ndarray
    position: np.ndarray
    range: np.ndarray
    significance: np.ndarray | None = None
    position_sigma: np.ndarray | None = None


def _pulse_bins(amp, tau, sigma, count):
    edges = np.arange(count + 1, dtype=float)
    z = (edges[None, :] - tau[:, None]) / (np.sqrt(2.0) * sigma)
    return amp[:, None] * np.diff(0.5 * erf(z), axis=1)


def _grid_start(h: np.ndarray, model, loglik) -> tuple[np.ndarray, np.ndarray]:
    """Start of the fit: (log amplitude, position (bins)) of each histogram, the best of a grid
    of positions around the histogram's peak and amplitudes."""
    n = len(h)
    peak = np.argmax(ndimage.uniform_filter1d(h, 3, axis=1), axis=1) + 0.5
    best_ll = np.full(n, -np.inf)
    la, start = np.zeros(n), peak.copy()
    for dt in np.arange(-2.0, 6.01, 0.5):
        for a in np.geomspace(0.05, 300.0, 19):
            cand = loglik(model(np.full(n, a), peak + dt))
            better = cand > best_ll
            best_ll = np.where(better, cand, best_ll)
            la = np.where(better, np.log(a), la)
            start = np.where(better, peak + dt, start)
    return la, start


def _gauss_newton_step(h, la, tau, mu, ll, model, loglik):
    """One Gauss-Newton step of (log amplitude, position) on the Poisson likelihood, with
    finite-difference derivatives; the step of a histogram whose likelihood fell is halved
    (up to 6 times). Returns the new ``(la, tau, mu, ll)``."""
    n = len(h)
    e1, e2 = 1e-4, 1e-3
    d_la = (model(np.exp(la + e1), tau) - mu) / e1
    d_t = (model(np.exp(la), tau + e2) - mu) / e2
    r = (h - mu) / mu
    q = 1.0 / mu
    f11, f12, f22 = (q * d_la**2).sum(1), (q * d_la * d_t).sum(1), (q * d_t**2).sum(1)
    g1, g2 = (r * d_la).sum(1), (r * d_t).sum(1)
    det = f11 * f22 - f12**2 + 1e-300
    s1 = np.clip((f22 * g1 - f12 * g2) / det, -1.0, 1.0)
    s2 = np.clip((f11 * g2 - f12 * g1) / det, -2.0, 2.0)
    step = np.ones(n)
    for _ in range(6):  # halve the step of the histograms whose likelihood fell
        cand_la, cand_t = la + step * s1, tau + step * s2
        cand_mu = model(np.exp(cand_la), cand_t)
        cand_ll = loglik(cand_mu)
        ok = cand_ll >= ll - 1e-9
        if ok.all():
            break
        step = np.where(ok, step, step / 2)
    la = np.where(ok, cand_la, la)
    tau = np.where(ok, cand_t, tau)
    mu = np.where(ok[:, None], cand_mu, mu)
    ll = np.where(ok, cand_ll, ll)
    return la, tau, mu, ll


def spad_correct(
    counts: np.ndarray,
    bins: TimeBins,
    *,
    pulses: int,
    dead_time_s: float,
    sigma_bins: float,
    background: np.ndarray | float = 0.0,
    iterations: int = 20,
) -> SpadFit:
    """Pile-up-corrected signal and position of a SPAD histogram's return (ML fit).

    The model: ``lambda_i = A G_i(tau) + b`` photons per pulse (``G_i`` a Gaussian pulse of
    ``sigma_bins`` integrated over bin i), seen through :func:`spad_expected`; ``A`` and
    ``tau`` maximise the Poisson likelihood of ``counts`` (Gauss-Newton with finite-difference
    derivatives, steps halved while the likelihood falls), started from the best point of a
    grid (positions -2 ... +6 bins from the histogram's peak, amplitudes 0.05-300 photons):
    a piled-up histogram's peak sits early, and a bigger pulse placed earlier is a local
    maximum of the likelihood that a start at the peak falls into.

    Parameters
    ----------
    counts : (..., count) int
        Detections per bin over ``pulses`` pulses.
    bins : TimeBins
    pulses : int
    dead_time_s : float
    sigma_bins : float
        The pulse's timing standard deviation in bins.
    background : (...) float or float
        Background photons per bin and pulse (sun and dark counts), known.
    iterations : int

    Returns
    -------
    SpadFit
    """
    h = np.asarray(counts, float)
    lead = h.shape[:-1]
    h = h.reshape(-1, bins.count)
    m = h.shape[1]
    b = np.broadcast_to(np.asarray(background, float), lead).reshape(-1)[:, None]

    def model(a, t):
        lam = _pulse_bins(a, t, sigma_bins, m) + b
        return np.maximum(spad_expected(lam, bins, dead_time_s=dead_time_s) * pulses, 1e-12)

    def loglik(mu):
        return (h * np.log(mu) - mu).sum(axis=1)

    la, tau = _grid_start(h, model, loglik)
    mu = model(np.exp(la), tau)
    ll = loglik(mu)
    for _ in range(iterations):
        la, tau, mu, ll = _gauss_newton_step(h, la, tau, mu, ll, model, loglik)
    amp = np.exp(la)
    ll0 = loglik(model(np.zeros(len(h)), tau))
    sig = np.sqrt(np.maximum(2.0 * (ll - ll0), 0.0))
    return SpadFit(
        photons=amp.reshape(lead),
        position=tau.reshape(lead),
        range=bins.range_of(tau).reshape(lead),
        significance=sig.reshape(lead),
        position_sigma=_position_sigma(la, tau, mu, model).reshape(lead),
    )


def _position_sigma(la, tau, mu, model) -> np.ndarray:
    """Standard error (bins) of the fitted position: ``sqrt((F^-1)_tt)`` of the Poisson
    Fisher information of (log amplitude, position) at the fit (finite differences)."""
    e1, e2 = 1e-4, 1e-3
    d_la = (model(np.exp(la + e1), tau) - mu) / e1
    d_t = (model(np.exp(la), tau + e2) - mu) / e2
    q = 1.0 / mu
    f11, f12, f22 = (q * d_la**2).sum(1), (q * d_la * d_t).sum(1), (q * d_t**2).sum(1)
    det = f11 * f22 - f12**2
    with np.errstate(divide="ignore", invalid="ignore"):
        var = np.where(det > 0, f11 / det, np.inf)
    return np.sqrt(var)


def spad_background(
    counts: np.ndarray,
    bins: TimeBins,
    *,
    pulses: int,
    dead_time_s: float,
    free_bins: np.ndarray | int,
    grid: int = 96,
) -> np.ndarray:
    """Background photons per bin and pulse estimated from a SPAD histogram's signal-free
    leading bins (never from the render's background).

    A detection in bin i depends only on the arrivals before it (the detector is armed at
    the window's start), so the first ``k`` bins of a histogram whose return lies later are
    the background alone, piled up by itself: their expected sum is
    ``pulses x sum_{i < k} spad_expected(b)_i``, increasing in the constant rate ``b``. That
    sum is tabulated on a log grid of ``b`` (1e-7 .. 10 photons per bin) and inverted by
    interpolation for each histogram's observed sum over its own ``k``.

    Parameters
    ----------
    counts : (n, count) int
        Detections per bin over ``pulses`` pulses.
    bins : TimeBins
    pulses : int
    dead_time_s : float
        Non-paralysable dead time (s), > 0 (inf: one detection per pulse).
    free_bins : (n,) int or int
        The signal-free leading bins of each histogram (those before its return); a
        histogram with none gets 0.
    grid : int
        Rates tabulated.

    Returns
    -------
    (n,) float64
        Background photons per bin and pulse.
    """
    h = np.asarray(counts, float).reshape(-1, bins.count)
    k = np.broadcast_to(np.asarray(free_bins, int), (len(h),)).clip(0, bins.count)
    kmax = int(k.max()) if len(k) else 0
    if kmax == 0:
        return np.zeros(len(h))
    rates = np.geomspace(1e-7, 10.0, grid)
    sub = TimeBins(bins.start_opl, bins.bin_opl, kmax)
    table = spad_expected(np.repeat(rates[:, None], kmax, axis=1), sub,
                          dead_time_s=dead_time_s)  # fmt: skip
    cum = np.concatenate([np.zeros((grid, 1)), np.cumsum(table, axis=1)], axis=1)  # (grid, k+1)
    observed = np.array([h[i, : k[i]].sum() / pulses for i in range(len(h))])
    out = np.zeros(len(h))
    for i in range(len(h)):
        if k[i] == 0:
            continue
        col = cum[:, k[i]]
        out[i] = (
            0.0
            if observed[i] <= 0
            else np.exp(
                np.interp(
                    observed[i], col, np.log(rates), left=np.log(rates[0]), right=np.log(rates[-1])
                )
            )
        )
    return out
