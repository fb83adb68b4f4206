"""Beam footprint: the cone of directions one laser shot illuminates and one receiver sees.

A real beam lights a spot, not a point: a ``divergence`` (full angle, at the 1/e^2 intensity
radius for a Gaussian beam, at the edge for a top-hat) widens it with range, and on a slope
the spot's near and far edges lie at different ranges, which spreads the return in time
(Gardner 1982). simlunar does not model this by formula: the renderer traces ``samples``
rays per beam whose directions are drawn from the beam's angular profile, and the transport
gives the waveform (mixed returns at depth edges included). :func:`cone_offsets` is the
profile's sampling map (the same one the renderer evaluates), and :func:`tilted_plane_spread`
the hand formula the tests check the rendered waveforms against.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.registry import Options, option

__all__ = [
    "PROFILES",
    "FootprintOptions",
    "cone_offsets",
    "footprint_radius",
    "spot_in_field",
    "tilted_plane_spread",
]

PROFILES = ("gaussian", "uniform")


@dataclass(frozen=True)
class FootprintOptions(Options):
    """Angular profile of one beam (laser spot times receiver field of view)."""

    divergence_rad: float = option(
        1e-3,
        doc="full divergence angle, in [0, pi/2): twice the 1/e^2 intensity half-angle for "
        "gaussian, the full cone angle for uniform; 0 = a single ray",
        unit="rad",
        key_unit="mrad",
        ge=0,
        lt=np.pi / 2,
    )
    profile: str = option(
        "gaussian", doc="radial intensity profile across the cone", choices=PROFILES
    )
    samples: int = option(
        16,
        doc="rays traced per beam (the footprint's Monte Carlo samples; the render's spp; at "
        "most 4096)",
        ge=1,
        le=4096,
    )

    @property
    def sigma_rad(self) -> float:
        """Standard deviation of the Gaussian profile per axis (rad): the 1/e^2 radius / 2."""
        return self.divergence_rad / 4.0


def cone_offsets(u: np.ndarray, options: FootprintOptions) -> np.ndarray:
    """Map uniform samples in [0, 1)^2 to angular offsets (rad) in the beam's cone.

    Gaussian: the radial offset is Rayleigh (Box-Muller), truncated at 3 sigma per radius
    (1.1 % of the energy, so no sample strays into the neighbouring beams' spots); uniform: a
    uniform disk of half-angle ``divergence_rad / 2``.

    Parameters
    ----------
    u : (n, 2) float
        Uniform samples.
    options : FootprintOptions

    Returns
    -------
    (n, 2) float64
        Small-angle offsets (rad) along two axes perpendicular to the beam.
    """
    u = np.asarray(u, float)
    phi = 2.0 * np.pi * u[:, 1]
    if options.profile == "gaussian":
        tail = np.exp(-4.5)  # truncate at r = 3 sigma
        r = options.sigma_rad * np.sqrt(-2.0 * np.log1p(-u[:, 0] * (1.0 - tail)))
    else:
        r = 0.5 * options.divergence_rad * np.sqrt(u[:, 0])
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


def spot_in_field(field_rad: float, options: FootprintOptions) -> float:
    """The share of a beam's spot (as :func:`cone_offsets` samples it) inside a concentric
    receiver field of full angle ``field_rad``.

    Gaussian (per-axis sigma ``s = divergence / 4``, truncated at 3 s): the radial offset is
    Rayleigh, so ``(1 - exp(-rho^2 / (2 s^2))) / (1 - exp(-4.5))`` with ``rho = field / 2``, i.e.
    ``1 - exp(-2 (field / divergence)^2)`` before the truncation (0.865 for a field equal to
    the divergence); uniform: ``(field / divergence)^2``; both at most 1.
    """
    if options.divergence_rad == 0:
        return 1.0
    rho = 0.5 * float(field_rad)
    if options.profile == "gaussian":
        s = options.sigma_rad
        if rho >= 3.0 * s:
            return 1.0
        return float(-np.expm1(-(rho**2) / (2.0 * s**2)) / -np.expm1(-4.5))
    return float(min(1.0, (rho / (0.5 * options.divergence_rad)) ** 2))


def footprint_radius(range_m, options: FootprintOptions) -> np.ndarray:
    """Radius (m) of the spot on a surface normal to the beam at ``range_m`` (1/e^2 or edge)."""
    return np.asarray(range_m, float) * np.tan(options.divergence_rad / 2.0)


def tilted_plane_spread(range_m: float, incidence_rad: float, options: FootprintOptions):
    """Standard deviation (m of range) of the return from a plane at incidence ``incidence_rad``.

    A ray at angular offset ``a`` in the plane of incidence meets the plane at range
    ``R cos(theta) / cos(theta - a)``, i.e. ``R (1 + a tan(theta))`` to first order: the
    range spreads as the offset's component along the tilt times ``R tan(theta)``. For the
    Gaussian profile (per-axis sigma ``s``, truncated at 3 s) and the uniform disk
    (half-angle ``h``: per-axis standard deviation ``h / 2``) that gives
    ``R tan(theta) * std(a)``. The return's weights over the footprint (``cos``, ``1/R^2``)
    vary by O(a) and are neglected.

    Returns
    -------
    float
        Standard deviation of the range over the footprint (m).
    """
    if options.profile == "gaussian":
        # per-axis variance of a 2-D Gaussian truncated at radius 3 sigma: E[r^2] / 2
        t = 4.5
        er2 = 2.0 * options.sigma_rad**2 * (1.0 - t * np.exp(-t) / (1.0 - np.exp(-t)))
        std_a = np.sqrt(er2 / 2.0)
    else:
        std_a = options.divergence_rad / 4.0
    return float(range_m * np.tan(incidence_rad) * std_a)
