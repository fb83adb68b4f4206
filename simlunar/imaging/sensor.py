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

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

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


def apply_sensor(radiance: np.ndarray, model: SensorModel, *, rng=None) -> np.ndarray:
    """Turn linear radiance into a noisy, quantised sensor image.

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
    rad = np.nan_to_num(np.asarray(radiance, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    mean_e = np.clip(rad, 0.0, None) * model.exposure
    # Poisson of a huge mean overflows int64; beyond the full well the pixel saturates anyway
    mean_e = np.minimum(mean_e, 16.0 * model.full_well_e + 1e6)
    # the full well clips the collected charge; read noise is added at readout, after it
    e = np.minimum(gen.poisson(mean_e).astype(np.float64), model.full_well_e)
    if model.read_noise_e > 0:
        e += gen.normal(0.0, model.read_noise_e, size=e.shape)
    dn = np.clip(np.round(e / model.gain_e_per_dn) + model.black_level, 0, model.max_dn)
    v = dn / model.max_dn
    if callable(model.response):
        out = np.asarray(model.response(v), dtype=np.float64)
        if out.shape != v.shape:
            raise ValueError(
                f"SensorModel.response callable changed the shape {v.shape} -> {out.shape}"
            )
        v = np.clip(out, 0.0, 1.0)
    elif model.response == "gamma":
        v = v ** (1.0 / model.gamma)
    return v.astype(np.float32)
