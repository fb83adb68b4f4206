"""BSDF ``lunar_lambert``: McEwen's lunar-Lambert reflectance, its spec and its Mitsuba plugin.

``f = rho / pi ((1 - L) + 2 L / (cos i + cos o))`` (McEwen 1991, Icarus 92, 298-311; the BRDF
of the photometric function ``I/F = A [(1 - L) cos i + 2 L cos i / (cos i + cos e)]``):
``L = 0`` is Lambert, ``L = 1`` Lommel-Seeliger normalised to ``rho / pi`` at normal
geometry, and every ``L`` gives ``rho / pi`` there, so ``rho`` is the normal albedo (the
terrain's albedo grid). The plugin evaluates exactly the formula of
:func:`simlunar.render.reference.lunar_lambert` (the tests compare them on an angle grid) in
Mitsuba's local shading frame; ``eval`` returns ``f * cos(theta_o)``. Sampling is
cosine-weighted over the upper hemisphere (:func:`~simlunar.render.plugins._common.
cosine_bsdf_base`). Lobe: diffuse reflection, front side only.

Parameters
----------

=============== ================= ========= ======== ===========================================
name            type              default   unit     meaning
=============== ================= ========= ======== ===========================================
``reflectance`` float or texture  0.5       1        normal albedo rho in [0, 1] (a ``bitmap``
                                                     of the terrain albedo grid in simlunar)
``L``           float             0.5       1        limb-darkening weight in [0, 1]: 0
                                                     Lambert, 1 Lommel-Seeliger
=============== ================= ========= ======== ===========================================

``L`` is an opaque constant: changing it through ``mi.traverse`` reuses the compiled kernels.
``mi.traverse`` exposes ``reflectance`` (differentiable) and ``L`` (not differentiable).

The spec :class:`LunarLambertBSDF` (NumPy only) is what the BSDF registry
(:data:`simlunar.render.materials.BSDFS`) and the YAML (``bsdf: {kind: lunar_lambert, L:
0.5}``) build; importing this module never imports Mitsuba.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from simlunar.registry import Options, option
from simlunar.render.plugins._common import INV_PI, opaque, register_plugin, scalar

__all__ = ["NAME", "LunarLambertBSDF", "register"]

NAME = "lunar_lambert"

_REGISTERED: set[str] = set()


@dataclass(frozen=True)
class LunarLambertBSDF(Options):
    """Lunar-Lambert reflectance (module docstring); the albedo is the terrain's grid.

    Parameters
    ----------
    L : float in [0, 1]
        Limb-darkening weight (0 Lambert, 1 Lommel-Seeliger).
    """

    L: float = option(0.5, doc="limb-darkening weight: 0 Lambert, 1 Lommel-Seeliger", ge=0, le=1)
    name = NAME

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(self, "L", float(self.L))

    def mitsuba_dict(self, reflectance: Any) -> dict:
        """The plugin's ``load_dict`` entry with ``reflectance`` as its normal albedo."""
        return {"type": NAME, "reflectance": reflectance, "L": self.L}


def _check_l(value: float) -> None:
    if not (math.isfinite(value) and 0.0 <= value <= 1.0):
        raise ValueError(f"{NAME}: L must be in [0, 1], got {value}")


def register(mi) -> None:
    """Define and register the plugin for the current variant (idempotent)."""
    register_plugin(mi, NAME, _REGISTERED, _plugin_class)


def _plugin_class(mi, base: type) -> type:
    """The plugin class for the current variant, a subclass of ``base`` (cosine sampling)."""
    import drjit as dr  # only once a Mitsuba variant is set

    class LunarLambertPlugin(base):
        """Lunar-Lambert BRDF; see :func:`simlunar.render.reference.lunar_lambert`."""

        def __init__(self, props):
            super().__init__(props)
            self.reflectance = props.get_texture("reflectance", 0.5)
            value = scalar(props, "L", 0.5)
            _check_l(value)
            self.L = opaque(mi, value)

        def _f(self, si, wo, active):
            rho = self.reflectance.eval(si, active)
            cos_i = mi.Frame3f.cos_theta(si.wi)
            cos_o = mi.Frame3f.cos_theta(wo)
            # cos_i + cos_o > 0 wherever the base class evaluates (both above the surface)
            g = (1.0 - self.L) + 2.0 * self.L / dr.maximum(cos_i + cos_o, 1e-7)
            return rho * (INV_PI * g)

        def traverse(self, callback):
            callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)
            callback.put("L", self.L, mi.ParamFlags.NonDifferentiable)

        def parameters_changed(self, keys):
            _check_l(float(self.L[0]))
            dr.make_opaque(self.L)

        def to_string(self):
            return f"LunarLambert[L={float(self.L[0]):.6g}, reflectance={self.reflectance}]"

    return LunarLambertPlugin
