"""Multi-frequency fringe phase (NumPy only): fringe periods, N-step wrapped phase and its noise,
temporal (hierarchical) unwrapping.

Formulas (N-step phase: Srinivasan, Liu & Halioua 1984, Appl. Opt. 23; noise and temporal
unwrapping: the reviews of Zuo et al., Opt. Lasers Eng. 2018 and 2016): from
``I_n = A + B cos(phi + 2 pi n / N)`` the
wrapped phase is ``phi = atan2(-sum I_n sin(2 pi n / N), sum I_n cos(2 pi n / N))``, the
modulation ``B = (2 / N) |sum I_n exp(-i 2 pi n / N)|`` and the phase noise of white frame noise
``sigma_I`` is ``sigma_phi = sqrt(2 / N) sigma_I / B``; unwrapping goes from the coarsest level up
with ``k_l = round((p_{l-1} / p_l Phi_{l-1} - phi_l) / (2 pi))``, ``Phi_l = phi_l + 2 pi k_l``.
The patterns and the decoder that use them: :mod:`simlunar.scanner.phase_shift`.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "fringe_periods",
    "phase_noise_std",
    "unwrap",
    "wrapped_phase",
]


#: the coarsest period is at least this many times the axis length (a margin of 5 % of the
#: period on each side, so noise cannot wrap the phase of the first or last pixel)
_COARSE_MARGIN = 1.1


def fringe_periods(n: int, period_px: float, ratio: float) -> tuple[float, ...]:
    """Fringe periods (projector px) of the unwrapping levels of an ``n``-pixel axis,
    coarsest first: ``period_px * ratio**j``, ``j = L-1 ... 0``, with the fewest levels whose
    coarsest period is at least 1.1 ``n`` (one unambiguous fringe over the axis)."""
    if n < 2:
        raise ValueError(f"a phase-shift axis needs at least 2 pixels, got {n}")
    if not period_px > 0 or not ratio > 1:
        raise ValueError(f"period_px must be > 0 and ratio > 1, got {period_px}, {ratio}")
    periods = [float(period_px)]
    while periods[-1] < _COARSE_MARGIN * n:
        periods.append(periods[-1] * ratio)
    return tuple(reversed(periods))


def wrapped_phase(frames) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wrapped phase, modulation and mean of ``N`` phase-shifted frames.

    Parameters
    ----------
    frames : (N, ...) array, N >= 3
        ``I_n = A + B cos(phi + 2 pi n / N)``.

    Returns
    -------
    phi : (...) float64 in [0, 2 pi)
        ``atan2(-sum I_n sin(2 pi n / N), sum I_n cos(2 pi n / N))``.
    modulation : (...) float64
        ``B = (2 / N) |sum I_n exp(-i 2 pi n / N)|``.
    mean : (...) float64
        ``A = sum I_n / N``.
    """
    frames = np.asarray(frames)
    N = frames.shape[0]
    if N < 3:
        raise ValueError(f"phase shifting needs at least 3 frames, got {N}")
    d = 2 * np.pi * np.arange(N) / N
    s = np.zeros(frames.shape[1:])
    c = np.zeros(frames.shape[1:])
    a = np.zeros(frames.shape[1:])
    for n in range(N):
        f = np.asarray(frames[n], np.float64)
        s += np.sin(d[n]) * f
        c += np.cos(d[n]) * f
        a += f
    phi = np.mod(np.arctan2(-s, c), 2 * np.pi)
    return phi, (2.0 / N) * np.hypot(s, c), a / N


def phase_noise_std(steps: int, sigma_i, modulation) -> np.ndarray:
    """Standard deviation of the wrapped phase for white frame noise (rad):
    ``sigma_phi = sqrt(2 / N) sigma_I / B`` (small-noise limit)."""
    return np.sqrt(2.0 / int(steps)) * np.asarray(sigma_i, float) / np.asarray(modulation, float)


def unwrap(phases, periods) -> tuple[np.ndarray, np.ndarray]:
    """Temporal (hierarchical) unwrapping, coarsest level first.

    Parameters
    ----------
    phases : sequence of (...) wrapped phases in [0, 2 pi), one per level
    periods : sequence of fringe periods (any unit), coarsest first; the coarsest phase is
        taken as unambiguous.

    Returns
    -------
    Phi : (...) float64
        Unwrapped phase of the finest level.
    disagreement : (...) float64
        Largest ``|p_{l-1} / p_l Phi_{l-1} - Phi_l|`` over the steps (rad; 0 for one level).
    """
    if len(phases) != len(periods) or not len(phases):
        raise ValueError(f"one phase per period needed, got {len(phases)} and {len(periods)}")
    big = np.asarray(phases[0], np.float64)
    worst = np.zeros_like(big)
    for lvl in range(1, len(phases)):
        phi = np.asarray(phases[lvl], np.float64)
        scaled = big * (periods[lvl - 1] / periods[lvl])
        k = np.round((scaled - phi) / (2 * np.pi))
        big = phi + 2 * np.pi * k
        worst = np.maximum(worst, np.abs(scaled - big))
    return big, worst
