"""BSDF ``lroc_empirical``: the LROC Empirical photometric function, its spec and its plugin.

The photometric function of USGS ISIS ``lronacpho`` (algorithm version 2019, fitted to more
than 760 000 LROC NAC image tiles; ``LROCEmpirical::photometry``), with ``mu0 = cos i``,
``mu = cos e`` and the phase angle ``a`` in degrees::

    F(i, e, a) = mu0 / (mu + mu0) exp(B0 + B1 a^2 + B2 a + B3 sqrt(a) + B4 mu + B5 mu0 + B6 mu0^2)

``F`` is the I/F of the average terrain of the fit; lronacpho normalises images to the
standard geometry ``i = 30, e = 0, a = 30`` deg by the factor ``F(30, 0, 30) / F(i, e, a)``
(:func:`simlunar.render.reference.lroc_empirical_correction`).

As a BSDF (:func:`simlunar.render.reference.lroc_empirical`): a facet of normal albedo ``A``
(the reflectance, i.e. the terrain's albedo grid) under a collimated beam of irradiance ``E``
normal to the beam returns the radiance ``L = E / pi * A F(i, e, a) / F(0, 0, 0)``: ``I/F = A``
seen and lit from straight above, as for lunar-Lambert and Hapke (normal albedo) and Lambert,
and the fit's angular shape everywhere else. The BRDF is ``f = L / (E cos i) = A / pi * 2 /
(mu + mu0) * exp(X(a, mu, mu0) - X(0, 1, 1))`` with ``X`` the exponent of ``F``; ``B0`` cancels
and is not a parameter. ``eval`` returns ``f * cos(theta_o)``.

The fit is not reciprocal (``B4 != B5``): in Mitsuba's ``Radiance`` mode ``wo`` points to the
light (``mu0 = cos theta_o``) and ``si.wi`` to the viewer; in ``Importance`` mode (light
tracing, ``ptracer``) the reverse; the plugin reads the mode from the BSDF context. Sampling is
cosine-weighted over the upper hemisphere, ``pdf = cos(theta_o) / pi``
(:func:`~simlunar.render.plugins._common.cosine_bsdf_base`). Lobe: diffuse reflection, front
side only.

Parameters
----------

=============== ================= ============== ======== ========================================
name            type              default        unit     meaning
=============== ================= ============== ======== ========================================
``reflectance`` float or texture  0.12           1        normal albedo A in [0, 1] (a ``bitmap``
                                                          of the terrain albedo grid in simlunar)
``B1``          float             -8.3528e-05    1        coefficient of a^2 (a in degrees)
``B2``          float             0.012964707    1        coefficient of a
``B3``          float             -0.237774774   1        coefficient of sqrt(a)
``B4``          float             0.556075496    1        coefficient of mu = cos e
``B5``          float             0.66367146     1        coefficient of mu0 = cos i
``B6``          float             -0.439918609   1        coefficient of mu0^2
=============== ================= ============== ======== ========================================

Defaults are :data:`simlunar.render.reference.LROC_EMPIRICAL_B` (B1..B6). The coefficients are
opaque constants: changing them through ``mi.traverse`` reuses the compiled kernels.
``mi.traverse`` exposes ``reflectance`` (differentiable) and ``B1``..``B6`` (not
differentiable).

The spec :class:`LROCEmpiricalBSDF` (NumPy only) is what the BSDF registry
(:data:`simlunar.render.materials.BSDFS`) and the YAML (``bsdf: {kind: lroc_empirical}``)
build; importing this module never imports Mitsuba.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from simlunar.registry import Options, option
from simlunar.render.plugins._common import INV_PI, opaque, register_plugin, scalar
from simlunar.render.reference import LROC_EMPIRICAL_B

__all__ = ["COEFFICIENTS", "NAME", "LROCEmpiricalBSDF", "register"]

NAME = "lroc_empirical"

#: the plugin's coefficient parameters (B0 cancels against the albedo normalisation)
COEFFICIENTS = ("B1", "B2", "B3", "B4", "B5", "B6")

_REGISTERED: set[str] = set()

_B = dict(zip(("B0", *COEFFICIENTS), LROC_EMPIRICAL_B, strict=True))


@dataclass(frozen=True)
class LROCEmpiricalBSDF(Options):
    """LROC Empirical photometric function (module docstring); the albedo is the terrain's
    grid (normal albedo). The coefficients default to the 2019 fit of ISIS ``lronacpho``."""

    B1: float = option(_B["B1"], doc="coefficient of the squared phase angle (degrees)")
    B2: float = option(_B["B2"], doc="coefficient of the phase angle (degrees)")
    B3: float = option(_B["B3"], doc="coefficient of the square root of the phase angle (degrees)")
    B4: float = option(_B["B4"], doc="coefficient of mu, the cosine of emission")
    B5: float = option(_B["B5"], doc="coefficient of mu0, the cosine of incidence")
    B6: float = option(_B["B6"], doc="coefficient of mu0 squared")
    name = NAME

    def __post_init__(self) -> None:
        super().__post_init__()
        for key in COEFFICIENTS:
            object.__setattr__(self, key, _finite(key, getattr(self, key)))

    @property
    def coefficients(self) -> tuple[float, ...]:
        """B0..B6 as :func:`simlunar.render.reference.lroc_empirical` takes them (B0, which
        cancels, the fit's)."""
        return (_B["B0"], *(getattr(self, k) for k in COEFFICIENTS))

    def mitsuba_dict(self, reflectance: Any) -> dict:
        """The plugin's ``load_dict`` entry with ``reflectance`` as its normal albedo."""
        return {
            "type": NAME,
            "reflectance": reflectance,
            **{k: getattr(self, k) for k in COEFFICIENTS},
        }


def _finite(key: str, value: Any) -> float:
    if isinstance(value, bool):
        raise ValueError(f"{NAME}: {key} must be a finite number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{NAME}: {key} must be a finite number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{NAME}: {key} must be a finite number, got {value!r}")
    return v


def register(mi) -> None:
    """Define and register the plugin for the current variant (idempotent)."""
    register_plugin(mi, NAME, _REGISTERED, _plugin_class)


def _plugin_class(mi, base: type) -> type:
    """The plugin class for the current variant, a subclass of ``base`` (cosine sampling)."""
    import drjit as dr  # only once a Mitsuba variant is set

    deg = 180.0 / math.pi

    class LROCEmpiricalPlugin(base):
        """LROC Empirical BRDF; see :func:`simlunar.render.reference.lroc_empirical`."""

        def __init__(self, props):
            super().__init__(props)
            self.reflectance = props.get_texture("reflectance", 0.12)
            for k in COEFFICIENTS:
                setattr(self, k, opaque(mi, _finite(k, scalar(props, k, _B[k]))))

        def _value(self, ctx, si, wo, active):
            rho = self.reflectance.eval(si, active)
            cos_wi = mi.Frame3f.cos_theta(si.wi)
            cos_wo = mi.Frame3f.cos_theta(wo)
            if ctx.mode == mi.TransportMode.Importance:
                mu0, mu = cos_wi, cos_wo  # light tracing: si.wi came from the light
            else:
                mu0, mu = cos_wo, cos_wi  # radiance: wo is the direction to the light
            mu0 = dr.clip(mu0, 0.0, 1.0)
            mu = dr.clip(mu, 0.0, 1.0)
            # phase angle in degrees; 2 atan2(|wi - wo|, |wi + wo|) is accurate at 0
            a = 2.0 * dr.atan2(dr.norm(si.wi - wo), dr.norm(si.wi + wo)) * deg
            x = (
                self.B1 * a * a
                + self.B2 * a
                + self.B3 * dr.sqrt(a)
                + self.B4 * (mu - 1.0)
                + self.B5 * (mu0 - 1.0)
                + self.B6 * (mu0 * mu0 - 1.0)
            )
            # mu + mu0 > 0 wherever the base class evaluates (both above the surface)
            g = 2.0 * dr.exp(x) / dr.maximum(mu + mu0, 1e-7)
            return rho * (INV_PI * g)

        def _f(self, si, wo, active):  # pragma: no cover - _value replaces it
            raise NotImplementedError("lroc_empirical evaluates through _value (mode-aware)")

        def traverse(self, callback):
            callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)
            for k in COEFFICIENTS:
                callback.put(k, getattr(self, k), mi.ParamFlags.NonDifferentiable)

        def parameters_changed(self, keys):
            for k in COEFFICIENTS:
                _finite(k, float(getattr(self, k)[0]))
                dr.make_opaque(getattr(self, k))

        def to_string(self):
            p = ", ".join(f"{k}={float(getattr(self, k)[0]):.9g}" for k in COEFFICIENTS)
            return f"LROCEmpirical[{p}, reflectance={self.reflectance}]"

    return LROCEmpiricalPlugin
