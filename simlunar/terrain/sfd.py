"""Cumulative size-frequency laws N(>D) for craters and rocks, and sampling from them.

All laws give the cumulative number of features with diameter larger than ``D`` (metres) per
square metre. Sources (the numbers are the ones used by NASA's synthterrain, Apache-2.0,
https://github.com/NeoGeographyToolkit/synthterrain):

- craters, Trask equilibrium: ``10**-1.1 * D**-2`` per m^2 (Trask 1966, Surveyor/Ranger counts);
- craters, VIPER environmental specification: ``29174 D**-1.92`` (D <= 80 m) and
  ``156228 D**-2.389`` (D > 80 m) per km^2;
- rocks, intercrater plains: ``1e-4 D**-1.75457``; VIPER spec: ``3e-4 D**-2.482``;
  high blockiness (Haworth): ``2e-3 D**-2.6607`` per m^2;
- ``power``: ``coefficient * D**-exponent`` per m^2 with user values;
- rocks, ``golombek``: the cumulative fractional area model of Golombek & Rapp (1997, JGR 102,
  E2), made for Mars landing sites and used for lunar ones: the share of the ground covered by
  rocks larger than ``D`` is ``F_k(D) = k exp(-q D)`` with ``q = 1.79 + 0.152 / k`` (``k`` the
  total rock area fraction, given as ``coefficient``). With ``n(D) = -dN/dD`` the number
  density, ``dF = -(pi D^2 / 4) dN``, so ``n(D) = (4 k q / pi) exp(-q D) / D^2`` and
  ``N(>D) = (4 k q / pi) (exp(-q D) / D - q E1(q D))`` (E1 the exponential integral).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np
from scipy.special import exp1

__all__ = [
    "CRATER_LAWS",
    "ROCK_LAWS",
    "expected_count",
    "get_law",
    "golombek_rocks",
    "power_law",
    "sample_diameters",
    "viper_craters",
]


def power_law(d: np.ndarray, *, coefficient: float, exponent: float) -> np.ndarray:
    """Cumulative density ``coefficient * D**-exponent`` (per m^2, D in m)."""
    return coefficient * np.asarray(d, dtype=np.float64) ** (-exponent)


def golombek_rocks(d: np.ndarray, *, k: float) -> np.ndarray:
    """Cumulative density N(>D) per m^2 (D in m) of the Golombek & Rapp (1997) model with total
    rock area fraction ``k`` (module docstring)."""
    d = np.asarray(d, dtype=np.float64)
    q = 1.79 + 0.152 / k
    return 4.0 * k * q / np.pi * (np.exp(-q * d) / d - q * exp1(q * d))


def viper_craters(d: np.ndarray) -> np.ndarray:
    """VIPER environmental specification for craters, per m^2 (two power-law segments)."""
    d = np.asarray(d, dtype=np.float64)
    small = 29174.0 * d ** (-1.92)
    large = 156228.0 * d ** (-2.389)
    return np.where(d <= 80.0, small, large) * 1e-6


#: cumulative crater laws N(>D) per m^2; "power" needs coefficient= and exponent=
CRATER_LAWS: dict[str, Callable] = {
    "trask": partial(power_law, coefficient=10**-1.1, exponent=2.0),
    "viper": viper_craters,
    "power": power_law,
}

#: cumulative rock laws N(>D) per m^2; "power" needs coefficient= and exponent=
ROCK_LAWS: dict[str, Callable] = {
    "intercrater": partial(power_law, coefficient=1e-4, exponent=1.75457),
    "viper": partial(power_law, coefficient=3e-4, exponent=2.482),
    "high_blockiness": partial(power_law, coefficient=2e-3, exponent=2.6607),
    "power": power_law,
    "golombek": golombek_rocks,
}


def get_law(kind: str, name: str, **params) -> Callable[[np.ndarray], np.ndarray]:
    """Return the cumulative law ``N(>D)`` (per m^2) named ``name`` for ``kind`` craters/rocks.

    ``power`` takes ``coefficient`` (> 0) and ``exponent`` (> 0); ``golombek`` (rocks) takes
    ``coefficient`` = k, the total rock area fraction in (0, 1); the named laws take no
    parameters. Unknown names raise ``ValueError`` listing the valid ones.
    """
    table = {"craters": CRATER_LAWS, "rocks": ROCK_LAWS}.get(kind)
    if table is None:
        raise ValueError(f"unknown feature kind {kind!r}; valid: craters, rocks")
    if name not in table:
        raise ValueError(f"unknown {kind} law {name!r}; valid: {', '.join(sorted(table))}")
    if name == "power":
        c, e = params.get("coefficient"), params.get("exponent")
        for key, v in (("coefficient", c), ("exponent", e)):
            if v is None or not np.isfinite(v) or v <= 0:
                raise ValueError(
                    f"{kind}.{key} must be a positive number for the power law, got {v!r}"
                )
        return partial(power_law, coefficient=float(c), exponent=float(e))
    if name == "golombek":
        k = params.get("coefficient")
        if k is None or not np.isfinite(k) or not 0 < k < 1:
            raise ValueError(
                f"{kind}.coefficient must be the rock area fraction k in (0, 1) for the "
                f"golombek law, got {k!r}"
            )
        if params.get("exponent") is not None:
            raise ValueError(f"{kind} law 'golombek' takes no exponent")
        return partial(golombek_rocks, k=float(k))
    extra = {k: v for k, v in params.items() if v is not None}
    if extra:
        raise ValueError(f"{kind} law {name!r} takes no parameters, got {sorted(extra)}")
    return table[name]


def _check_range(d_min: float, d_max: float, what: str) -> None:
    if not (np.isfinite(d_min) and d_min > 0):
        raise ValueError(f"{what}.d_min_m must be a positive number of metres, got {d_min!r}")
    if not (np.isfinite(d_max) and d_max > d_min):
        raise ValueError(
            f"{what} diameter range is empty: d_max_m ({d_max!r}) must exceed d_min_m ({d_min!r})"
        )


def expected_count(law: Callable, area_m2: float, d_min: float, d_max: float) -> float:
    """Expected number of features with ``d_min < D <= d_max`` over ``area_m2``."""
    _check_range(d_min, d_max, "features")
    return float(area_m2 * (law(d_min) - law(d_max)))


def sample_diameters(
    law: Callable, area_m2: float, d_min: float, d_max: float, *, rng=None, what: str = "features"
) -> np.ndarray:
    """Draw a Poisson population of diameters from a cumulative law.

    The count is Poisson with mean ``area * (N(d_min) - N(d_max))``; each diameter is drawn by
    inverting the truncated cumulative law (log-log interpolation on a fine grid, exact for
    power-law segments).

    Parameters
    ----------
    law : callable
        ``N(>D)`` per m^2, decreasing.
    area_m2 : float
        Area over which features are placed (m^2).
    d_min, d_max : float
        Diameter range in metres.
    rng : seed or Generator

    Returns
    -------
    (n,) float64 array of diameters in metres, in random order.
    """
    _check_range(d_min, d_max, what)
    gen = np.random.default_rng(rng)
    n = gen.poisson(max(expected_count(law, area_m2, d_min, d_max), 0.0))
    grid = np.geomspace(d_min, d_max, 4097)
    cum = np.asarray(law(grid), dtype=np.float64)
    if np.any(np.diff(cum) > 0) or np.any(cum <= 0):
        raise ValueError(f"{what} law must be positive and decreasing over [{d_min}, {d_max}] m")
    u = gen.uniform(cum[-1], cum[0], size=n)
    # np.interp needs increasing x: interpolate log D against log N reversed
    return np.exp(np.interp(np.log(u), np.log(cum[::-1]), np.log(grid[::-1])))
