"""Camera sensor model applied to rendered linear radiance (after rendering, own rng).

Chain per pixel (the standard photon-transfer model, e.g. EMVA 1288):

1. electrons ``e = exposure * radiance`` (mean signal; ``exposure`` folds in aperture,
   integration time and quantum efficiency),
2. shot noise ``Poisson(e)``, clipped at ``full_well_e`` (saturation of the pixel),
3. Gaussian read noise ``N(0, read_noise_e**2)`` added at readout,
4. ADC: ``DN = round(e / gain) + black_level`` clipped to ``[0, 2**bits - 1]``,
5. normalisation ``DN / (2**bits - 1)`` and the response curve (linear, gamma or any callable
   mapping [0, 1] to [0, 1]).

The output is a float32 image in [0, 1] with at most ``2**bits`` distinct values.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = ["POISSON_EXACT_BELOW", "RESPONSES", "SensorModel", "apply_sensor", "poisson_from_normal"]

RESPONSES = ("linear", "gamma")


@dataclass(frozen=True)
class SensorModel:
    """Parameters of a linear photon-transfer sensor.

    Parameters
    ----------
    exposure : float
        Electrons per unit of linear radiance (> 0).
    full_well_e : float
        Saturation capacity in electrons (> 0).
    read_noise_e : float
        Standard deviation of the read noise in electrons (>= 0).
    bits : int
        ADC resolution, 1..32.
    gain : float, optional
        Electrons per digital number (DN). ``None`` maps the full well onto the ADC range:
        ``full_well_e / (2**bits - 1)``.
    black_level : int
        Offset in DN added before clipping (>= 0); read noise then shows below it.
    response : {"linear", "gamma"} or callable
        Response curve applied to the normalised value v in [0, 1]; ``"gamma"`` gives
        ``v ** (1 / gamma)``; a callable gets and must return arrays in [0, 1].
    gamma : float
        Exponent for ``response="gamma"`` (> 0).
    """

    exposure: float = 1000.0
    full_well_e: float = 20000.0
    read_noise_e: float = 5.0
    bits: int = 12
    gain: float | None = None
    black_level: int = 0
    response: str | Callable[[np.ndarray], np.ndarray] = "linear"
    gamma: float = 2.2

    def __post_init__(self) -> None:
        def positive(name):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"SensorModel.{name} must be a positive number, got {v!r}")

        for name in ("exposure", "full_well_e", "gamma"):
            positive(name)
        if not (np.isfinite(self.read_noise_e) and self.read_noise_e >= 0):
            raise ValueError(f"SensorModel.read_noise_e must be >= 0, got {self.read_noise_e!r}")
        if (
            isinstance(self.bits, bool)
            or not isinstance(self.bits, (int, np.integer))
            or not (1 <= self.bits <= 32)
        ):
            raise ValueError(f"SensorModel.bits must be an integer in 1..32, got {self.bits!r}")
        if self.gain is not None:
            positive("gain")
        if not (isinstance(self.black_level, (int, np.integer)) and 0 <= self.black_level):
            raise ValueError(
                f"SensorModel.black_level must be a non-negative integer DN, got {self.black_level!r}"
            )
        if self.black_level > self.max_dn:
            raise ValueError(
                f"SensorModel.black_level {self.black_level} exceeds the ADC maximum {self.max_dn}"
            )
        if not callable(self.response) and self.response not in RESPONSES:
            raise ValueError(
                f"SensorModel.response must be one of {', '.join(RESPONSES)} or a callable, "
                f"got {self.response!r}"
            )

    @property
    def max_dn(self) -> int:
        """Largest digital number, ``2**bits - 1``."""
        return (1 << int(self.bits)) - 1

    @property
    def gain_e_per_dn(self) -> float:
        """Electrons per DN actually used."""
        return float(self.gain) if self.gain is not None else self.full_well_e / self.max_dn


#: below this many mean electrons the shot noise is drawn exactly (inverse Poisson CDF); at
#: and above it from the Cornish-Fisher corrected normal approximation (mean and third cumulant
#: of the Poisson law, variance mu + 1/18)
POISSON_EXACT_BELOW = 50.0


def apply_sensor(radiance: np.ndarray, model: SensorModel, *, rng=None) -> np.ndarray:
    """Turn linear radiance into a noisy, quantised sensor image.

    Runs as one compiled pass per pixel (numba) on float32 arrays, with float64 arithmetic
    inside. Shot noise: a pixel with mean ``mu`` electrons gets an exact Poisson draw
    (inverse CDF) for ``mu < POISSON_EXACT_BELOW`` and ``mu + sqrt(mu) z + (z**2 - 1) / 6``
    (normal ``z``; the Cornish-Fisher expansion of the Poisson law: exact mean and third
    cumulant, variance ``mu + 1/18``) above; the random numbers come from ``rng`` (one float32
    normal per pixel for the shot noise, one for the read noise), so equal seeds give equal
    images.

    Parameters
    ----------
    radiance : array, any shape (e.g. (rows, cols) or (rows, cols, 3))
        Linear radiance (>= 0; negative values and NaN count as 0).
    model : SensorModel
        The sensor.
    rng : seed or numpy Generator
        Noise source (``np.random.default_rng(rng)``); the renderer's seed is not reused.

    Returns
    -------
    float32 array, same shape, values in [0, 1]
    """
    if not isinstance(model, SensorModel):
        raise ValueError(f"model must be a SensorModel, got {type(model).__name__}")
    gen = np.random.default_rng(rng)
    rad = np.asarray(radiance)
    if rad.dtype not in (np.float32, np.float64):
        rad = rad.astype(np.float64)
    flat = np.ascontiguousarray(rad).reshape(-1)
    shot_z = gen.standard_normal(flat.size, dtype=np.float32)
    read_z = (
        gen.standard_normal(flat.size, dtype=np.float32)
        if model.read_noise_e > 0
        else np.zeros(1, np.float32)
    )
    gamma_inv = 1.0 / model.gamma if model.response == "gamma" else 0.0
    out = np.empty(flat.size, np.float32)
    _sensor_kernel(
        flat,
        shot_z,
        read_z,
        out,
        float(model.exposure),
        # Poisson of a huge mean overflows; beyond the full well the pixel saturates anyway
        16.0 * model.full_well_e + 1e6,
        float(model.full_well_e),
        float(model.read_noise_e),
        float(model.gain_e_per_dn),
        float(model.black_level),
        float(model.max_dn),
        gamma_inv,
        POISSON_EXACT_BELOW,
    )
    out = out.reshape(rad.shape)
    if callable(model.response):
        v = out.astype(np.float64)
        res = np.asarray(model.response(v), dtype=np.float64)
        if res.shape != v.shape:
            raise ValueError(
                f"SensorModel.response callable changed the shape {v.shape} -> {res.shape}"
            )
        out = np.clip(res, 0.0, 1.0).astype(np.float32)
    return out


def poisson_from_normal(mu: float, z: float, exact_below: float = POISSON_EXACT_BELOW) -> float:
    """One shot-noise draw as :func:`apply_sensor` makes it (for tests and single pixels).

    ``mu`` mean electrons, ``z`` a standard normal number.
    """
    return float(_poisson_from_normal(float(mu), float(z), float(exact_below)))


@njit(cache=True, nogil=True)
def _poisson_from_normal(mu, z, exact_below):  # pragma: no cover - compiled
    if mu <= 0.0:
        return 0.0
    if mu >= exact_below:
        return max(mu + math.sqrt(mu) * z + (z * z - 1.0) / 6.0, 0.0)
    # exact: the smallest k with CDF(k) >= u, u = Phi(z) uniform on (0, 1)
    u = 0.5 * math.erfc(-z / math.sqrt(2.0))
    p = math.exp(-mu)
    c = p
    k = 0
    kmax = mu + 20.0 * math.sqrt(mu) + 30.0
    while c < u and k < kmax:
        k += 1
        p *= mu / k
        c += p
    return float(k)


@njit(cache=True, nogil=True)
def _sensor_kernel(
    rad,
    shot_z,
    read_z,
    out,
    exposure,
    cap,
    full_well,
    read_noise,
    gain,
    black,
    max_dn,
    gamma_inv,
    exact_below,
):  # pragma: no cover - compiled
    has_read = read_noise > 0.0
    for i in range(rad.size):
        r = float(rad[i])
        if not (r > 0.0) or math.isinf(r):  # NaN, negative, zero and inf count as 0
            r = 0.0
        mu = min(r * exposure, cap)
        # the full well clips the collected charge; read noise is added at readout, after it
        e = min(_poisson_from_normal(mu, shot_z[i], exact_below), full_well)
        if has_read:
            e += read_noise * read_z[i]
        dn = min(max(np.rint(e / gain) + black, 0.0), max_dn)
        v = dn / max_dn
        if gamma_inv > 0.0:
            v = v**gamma_inv
        out[i] = v
