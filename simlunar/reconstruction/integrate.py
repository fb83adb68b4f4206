"""Fields on the mirror-extended grid: Frankot-Chellappa integration and Gaussian smoothing.

Both treat a (rows, cols) field as one quarter of its mirror extension (the half-sample even
extension of size 2R x 2C, periodic): no wrap-around seam at the edges.

:func:`frankot_chellappa` is the least-squares integrator of Frankot & Chellappa (IEEE PAMI
10(4), 1988: project the slope field onto the integrable fields in the Fourier domain) on the
FFT of that mirror extension, with the central difference's frequency response ``i sin(w)``
(so the gradient of any field by :func:`central_gradient` integrates back to it exactly), and
an optional weight on the slope across a chosen direction (the image gives the slope along the
light, the samples only a smooth slope across it). :func:`gaussian_smooth` works in the cosine
(DCT-II) domain, the Fourier domain of the even extension, at half the FFT's size.
"""

from __future__ import annotations

import os

import numpy as np
import scipy.fft as sfft

__all__ = ["central_gradient", "frankot_chellappa", "gaussian_smooth"]

_WORKERS = max(1, min(4, os.cpu_count() or 1))


def _dct(a):
    return sfft.dctn(a, type=2, norm="ortho", workers=_WORKERS)


def _idct(a):
    return sfft.idctn(a, type=2, norm="ortho", workers=_WORKERS)


def _freqs(n: int) -> np.ndarray:
    """Angular frequency (rad / cell) of each DCT-II coefficient of a length-n axis."""
    return np.pi * np.arange(n) / n


def _field(a, name: str) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.ndim != 2 or a.size == 0:
        raise ValueError(f"{name} must be a non-empty (rows, cols) array, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name} contains NaN or infinite values")
    return a


def gaussian_smooth(a, sigma: float) -> np.ndarray:
    """Gaussian smoothing of a field mirrored about its edges.

    Equals ``scipy.ndimage.gaussian_filter(a, sigma, mode="reflect")`` with an untruncated
    kernel (to the kernel's sampling: the transfer function is the continuous Gaussian's,
    ``exp(-sigma^2 w^2 / 2)``), at about half its cost for sigma >= 4.

    Parameters
    ----------
    a : array_like, shape (rows, cols)
    sigma : float
        Standard deviation in cells (>= 0; 0 returns a copy).

    Returns
    -------
    ndarray of float64, shape (rows, cols)
    """
    a = _field(a, "a")
    if not np.isfinite(sigma) or sigma < 0:
        raise ValueError(f"sigma must be a finite number >= 0, got {sigma!r}")
    if sigma == 0:
        return a.copy()
    gr = np.exp(-0.5 * (sigma * _freqs(a.shape[0])) ** 2)
    gc = np.exp(-0.5 * (sigma * _freqs(a.shape[1])) ** 2)
    f = _dct(a)
    f *= gr[:, None]
    f *= gc[None, :]
    return _idct(f)


def central_gradient(z) -> tuple[np.ndarray, np.ndarray]:
    """Central differences with mirrored edges: the operator :func:`frankot_chellappa` inverts.

    ``gr[i] = (z[i + 1] - z[i - 1]) / 2`` with ``z[-1] = z[0]`` and ``z[rows] = z[rows - 1]``
    (the half-sample mirror extension), likewise along columns.

    Returns
    -------
    gr, gc : ndarray, shape (rows, cols)
        d z / d row and d z / d col (value per cell).
    """
    z = _field(z, "z")
    zr = np.concatenate((z[:1], z, z[-1:]), axis=0)
    zc = np.concatenate((z[:, :1], z, z[:, -1:]), axis=1)
    return 0.5 * (zr[2:] - zr[:-2]), 0.5 * (zc[:, 2:] - zc[:, :-2])


def _mirror(m, n):
    """The 2R x 2C mirror extension of ``m + n`` where ``m`` is odd about the row edges
    (a d/d row component) and ``n`` odd about the column edges (a d/d col component)."""
    rows, cols = m.shape
    out = np.empty((2 * rows, 2 * cols))
    out[:rows, :cols] = m + n
    out[:rows, cols:] = (m - n)[:, ::-1]
    out[rows:, :cols] = (n - m)[::-1]
    out[rows:, cols:] = -out[:rows, :cols][::-1, ::-1]
    return out


def frankot_chellappa(
    gr, gc, *, along=None, across_weight: float = 1.0, detrend: bool = True
) -> np.ndarray:
    """Integrate a cell-centred slope field (Frankot-Chellappa on the mirror-extended field).

    Minimises ``|u . (grad z - g)|^2 + w |t . (grad z - g)|^2`` summed over the mirror
    extension of the grid, ``grad`` being central differences (:func:`central_gradient`),
    ``u`` the unit ``along`` direction, ``t`` across it and ``w`` the ``across_weight``
    (``w = 1``: the isotropic Frankot-Chellappa projection, whatever ``u``). Per Fourier mode
    of the 2R x 2C extension, with ``K = i sin(omega)`` the central difference's response,
    ``A = u . K`` and ``B = t . K``::

        Z = (conj(A) (u . G) + w conj(B) (t . G)) / (|A|^2 + w |B|^2)

    A small ``w`` trusts the slope along ``u`` and keeps every mode's amplitude along it (the
    isotropic projection keeps only ``cos^2`` of the angle between a mode and ``u`` when the
    slope across is smoother than the truth).

    Parameters
    ----------
    gr, gc : array_like, shape (rows, cols)
        d z / d row and d z / d col at each cell (value per cell).
    along : array_like, shape (2,), optional
        (row, col) direction ``u``; default (1, 0).
    across_weight : float
        ``w`` > 0.
    detrend : bool
        Integrate the mean slope as an exact plane and only the rest by Fourier (so a constant
        slope field gives its plane to rounding; the mirror extension would make it a
        triangle wave).

    Returns
    -------
    ndarray of float64, shape (rows, cols)
        Mean zero. Without ``detrend`` the gradient of any field by :func:`central_gradient`
        integrates back to that field (less its mean) to rounding.
    """
    gr = _field(gr, "gr")
    gc = _field(gc, "gc")
    if gr.shape != gc.shape:
        raise ValueError(f"gr and gc must have the same shape, got {gr.shape} and {gc.shape}")
    if not (np.isfinite(across_weight) and across_weight > 0):
        raise ValueError(f"across_weight must be a finite number > 0, got {across_weight!r}")
    u = np.array([1.0, 0.0]) if along is None else np.asarray(along, dtype=np.float64)
    if u.shape != (2,) or not np.isfinite(u).all() or np.hypot(*u) == 0:
        raise ValueError(f"along must be a non-zero (row, col) direction, got {along!r}")
    u = u / np.hypot(*u)
    t = np.array([-u[1], u[0]])
    rows, cols = gr.shape
    plane = None
    if detrend:
        mr, mc = float(gr.mean()), float(gc.mean())
        gr, gc = gr - mr, gc - mc
        rr = np.arange(rows) - 0.5 * (rows - 1)
        cc = np.arange(cols) - 0.5 * (cols - 1)
        plane = mr * rr[:, None] + mc * cc[None, :]
    kr = np.sin(2.0 * np.pi * sfft.fftfreq(2 * rows))[:, None]
    kc = np.sin(2.0 * np.pi * sfft.rfftfreq(2 * cols))[None, :]
    a = u[0] * kr + u[1] * kc  # A = i a
    b = t[0] * kr + t[1] * kc
    den = a * a + across_weight * (b * b)
    fu = sfft.rfft2(_mirror(u[0] * gr, u[1] * gc), workers=_WORKERS)
    ft = sfft.rfft2(_mirror(t[0] * gr, t[1] * gc), workers=_WORKERS)
    # conj(i a) = -i a
    fu *= a
    ft *= across_weight * b
    fu += ft
    del ft
    small = den <= 1e-12
    den[small] = 1.0
    fu *= -1j / den
    fu[small] = 0.0
    z = sfft.irfft2(fu, s=(2 * rows, 2 * cols), workers=_WORKERS)[:rows, :cols]
    z -= z.mean()
    if plane is not None:
        z += plane
    return z
