"""Simple craters: placement, fresh profile, degradation by diffusion, superposition.

Fresh simple crater of diameter D (radius R = D/2), heights relative to the pre-impact surface:

- rim-crest-to-floor depth ``d = 0.196 D**1.01`` and rim height ``h = 0.036 D**1.014``
  (Pike 1977, fresh lunar simple craters, as in NASA's synthterrain);
- bowl (r = dist / R <= 1): ``z = h - d + d r**2`` (parabolic, floor at ``h - d``, rim crest at r = 1);
- ejecta blanket (r > 1): ``z = h r**-3`` tapered to zero at ``r = 3`` (thickness decaying as the
  inverse cube of distance, McGetchin et al. 1973).

Degradation: topographic diffusion ``dz/dt = kappa lap z`` (Soderblom 1970; Fassett & Thomson
2014 measured kappa ~ 5.5 m^2/Myr for lunar craters) turns the profile into its convolution with a
Gaussian of standard deviation ``sqrt(2 kappa t)``. Diffusion is linear, so a degraded crater is
``h * E_s(r) + d * B_s(r)``, where ``E`` and ``B`` are the rim/ejecta and bowl shapes diffused with
``s = sqrt(2 kappa t) / R``; those are tabulated once on a normalised grid.

Superposition in order of formation (oldest first): each crater adds its profile and, inside its
bowl, partly erases the older relief (weight ``1 - r**2``, shrinking as the crater degrades), so a
young crater cuts the craters it lands on.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import lru_cache

import numpy as np

from simlunar.terrain._window import feature_window

__all__ = [
    "EJECTA_END",
    "S_MAX",
    "Crater",
    "crater_profile",
    "extent_radii",
    "fresh_depth",
    "fresh_rim_height",
    "place_craters",
    "stamp_craters",
]

#: ejecta taper radius (in crater radii)
EJECTA_END = 3.0
#: largest tabulated relative diffusion length s = sqrt(2 kappa t) / R; beyond it the crater is
#: so subdued (relief under ~15 % of fresh) that it is not stamped
S_MAX = 1.0
_N_LEVELS = 33
_HALF = 7.0  # normalised table half-width (radii): ejecta end + 3 s_max + margin
_STEP = 1.0 / 40.0


def fresh_depth(d: np.ndarray) -> np.ndarray:
    """Rim-crest-to-floor depth of a fresh simple crater, ``0.196 D**1.01`` (Pike 1977), m."""
    return 0.196 * np.asarray(d, dtype=np.float64) ** 1.01


def fresh_rim_height(d: np.ndarray) -> np.ndarray:
    """Rim height above the surroundings, ``0.036 D**1.014`` (Pike 1977), m."""
    return 0.036 * np.asarray(d, dtype=np.float64) ** 1.014


def _fresh_shapes(r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normalised rim/ejecta shape E(r) and bowl shape B(r): z = h E + d B."""
    r = np.asarray(r, dtype=np.float64)
    e_end = EJECTA_END**-3
    with np.errstate(divide="ignore"):
        ej = (np.maximum(r, 1.0) ** -3 - e_end) / (1.0 - e_end)
    E = np.where(r <= 1.0, 1.0, np.where(r < EJECTA_END, ej, 0.0))
    B = np.where(r <= 1.0, r**2 - 1.0, 0.0)
    return E, B


def crater_profile(r: np.ndarray, diameter: float, s: float = 0.0) -> np.ndarray:
    """Height change (m) at normalised radius ``r = dist / R`` for a crater of ``diameter`` m.

    ``s`` is the relative diffusion length ``sqrt(2 kappa t) / R`` (0 = fresh).
    """
    h, d = fresh_rim_height(diameter), fresh_depth(diameter)
    if s <= 0:
        E, B = _fresh_shapes(r)
    else:
        E, B = _degraded_shapes(np.asarray(r, dtype=np.float64), s)
    return h * E + d * B


@lru_cache(maxsize=1)
def _table() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Radial tables of E and B diffused with s on ``_N_LEVELS`` levels in [0, S_MAX].

    The 2-D shapes are blurred exactly in the Fourier domain (Gaussian transfer function
    ``exp(-2 pi^2 s^2 |k|^2)``); only the row through the centre is inverse-transformed, so each
    level costs one weighted sum instead of a full 2-D filter. The table is wide enough
    (``_HALF`` radii) that the blurred blanket never wraps around.
    """
    n = round(_HALF / _STEP)
    size = 2 * n + 1
    ax = np.arange(-n, n + 1) * _STEP
    X, Y = np.meshgrid(ax, ax)
    E2, B2 = _fresh_shapes(np.hypot(X, Y))
    ky = np.fft.fftfreq(size, d=_STEP)[:, None]
    kx = np.fft.rfftfreq(size, d=_STEP)[None, :]
    k2 = ky**2 + kx**2
    # inverse FFT along rows evaluated only at row n (the centre row)
    phase = np.exp(2j * np.pi * np.fft.fftfreq(size) * n)[:, None] / size
    FE, FB = np.fft.rfft2(E2), np.fft.rfft2(B2)
    levels = np.linspace(0.0, S_MAX, _N_LEVELS)
    radial = ax[n:]
    Et = np.empty((_N_LEVELS, radial.size))
    Bt = np.empty_like(Et)
    for i, s in enumerate(levels):
        if s == 0:
            Et[i], Bt[i] = _fresh_shapes(radial)
            continue
        g = np.exp(-2.0 * np.pi**2 * s**2 * k2) * phase
        Et[i] = np.fft.irfft((FE * g).sum(0), n=size)[n:]
        Bt[i] = np.fft.irfft((FB * g).sum(0), n=size)[n:]
    return levels, radial, Et, Bt


def _degraded_shapes(r: np.ndarray, s: float) -> tuple[np.ndarray, np.ndarray]:
    _levels, radial, Et, Bt = _table()
    f = np.clip(s, 0.0, S_MAX) / S_MAX * (_N_LEVELS - 1)
    i0 = min(int(f), _N_LEVELS - 2)
    w = f - i0
    E = (1 - w) * Et[i0] + w * Et[i0 + 1]
    B = (1 - w) * Bt[i0] + w * Bt[i0 + 1]
    # linear interpolation in r on the regular table grid
    x = np.clip(r / _STEP, 0.0, radial.size - 1.000001)
    j = x.astype(np.int64)
    t = x - j
    return (1 - t) * E[j] + t * E[j + 1], (1 - t) * B[j] + t * B[j + 1]


def extent_radii(s: float) -> float:
    """Radius (in crater radii) beyond which a crater degraded by ``s`` changes nothing."""
    return min(EJECTA_END + 3.0 * s, _HALF)


@dataclass(frozen=True)
class Crater:
    """One placed crater (world coordinates, metres; age in Myr before present)."""

    x: float
    y: float
    diameter: float
    depth: float
    rim_height: float
    age_myr: float
    degradation: float  # s = sqrt(2 kappa t) / R
    visible: bool  # False: degraded beyond S_MAX and not stamped

    def to_dict(self) -> dict:
        return {k: (float(v) if not isinstance(v, bool) else v) for k, v in asdict(self).items()}


def place_craters(
    diameters: np.ndarray,
    *,
    extent: tuple[float, float, float, float],
    diffusivity: float,
    max_age_myr: float,
    rng=None,
) -> list[Crater]:
    """Poisson positions and uniform ages for given diameters, sorted oldest first.

    Centres are uniform over ``extent`` (xmin, xmax, ymin, ymax); the caller enlarges the extent
    so craters cut by the border are included. The diameters are taken as the *visible*
    population (equilibrium laws such as Trask's count visible craters), so each crater's age is
    uniform over its visible lifetime ``t_life = (S_MAX R)**2 / (2 kappa)`` capped at
    ``max_age_myr`` (a young surface: every crater fresher). Depth and rim height are the values
    after diffusion (relief of the degraded profile).
    """
    gen = np.random.default_rng(rng)
    d = np.asarray(diameters, dtype=np.float64)
    n = d.size
    xmin, xmax, ymin, ymax = extent
    x = gen.uniform(xmin, xmax, n)
    y = gen.uniform(ymin, ymax, n)
    with np.errstate(divide="ignore"):
        life = np.where(diffusivity > 0, (S_MAX * d / 2.0) ** 2 / (2.0 * diffusivity), np.inf)
    age = gen.uniform(0.0, 1.0, n) * np.minimum(life, max_age_myr)
    s = np.sqrt(2.0 * diffusivity * age) / (d / 2.0)
    order = np.argsort(-age, kind="stable")
    out = []
    for i in order:
        si = float(s[i])
        vis = si <= S_MAX
        prof = crater_profile(np.array([0.0, 1.0]), d[i], min(si, S_MAX))
        out.append(
            Crater(
                x=float(x[i]),
                y=float(y[i]),
                diameter=float(d[i]),
                depth=float(prof[1] - prof[0]),
                rim_height=float(prof[1]),
                age_myr=float(age[i]),
                degradation=si,
                visible=bool(vis),
            )
        )
    return out


def stamp_craters(
    heights: np.ndarray,
    craters: list[Crater],
    *,
    spacing: float,
    origin: tuple[float, float],
    freshness: np.ndarray | None = None,
) -> np.ndarray:
    """Superpose craters in list order (oldest first) on ``heights`` in place; returns it.

    Each crater touches only its bounding window (``extent_radii`` crater radii). If given,
    ``freshness`` (same shape, in [0, 1]) receives the brightness weight of fresh ejecta:
    ``(1 - s / S_MAX)**3`` fading linearly from the rim to the end of the ejecta blanket
    (immature, fresh ejecta is brighter than mature soil).
    """
    for c in craters:
        if not c.visible:
            continue
        R = c.diameter / 2.0
        ext = extent_radii(c.degradation) * R
        w = feature_window(c.x, c.y, ext, heights.shape, spacing, origin)
        if w is None:
            continue
        rs, cs, dx, dy = w
        r = np.hypot(dy[:, None], dx[None, :]) / R
        win = heights[rs, cs]
        delta = crater_profile(r, c.diameter, c.degradation)
        inside = r < 1.0
        if np.any(inside):
            # the impact excavates the older relief inside the bowl: pull it towards its mean
            erase = np.where(inside, 1.0 - r**2, 0.0) * max(0.0, 1.0 - c.degradation / S_MAX)
            ref = win[inside].mean()
            win -= erase * (win - ref)
        win += delta
        if freshness is not None:
            f = (1.0 - c.degradation / S_MAX) ** 3
            if f > 0.01:
                fw = f * np.clip((EJECTA_END - r) / (EJECTA_END - 1.0), 0.0, 1.0)
                fwin = freshness[rs, cs]
                np.maximum(fwin, fw, out=fwin)
    return heights
