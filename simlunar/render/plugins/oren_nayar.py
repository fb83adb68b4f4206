"""Mitsuba BSDF plugin ``oren_nayar``: the Oren-Nayar (1994) rough diffuse BRDF.

Evaluates exactly the formulas of :func:`simlunar.render.reference.oren_nayar` (the tests
compare them on an angle grid) in Mitsuba's local shading frame (z = shading normal, ``si.wi``
towards the previous vertex, ``wo`` the other direction); ``eval`` returns ``f * cos(theta_o)``
like every Mitsuba BSDF. Sampling is cosine-weighted over the upper hemisphere (independent of
the parameters). Lobe: diffuse reflection, front side only.

Parameters
----------

=============== =================== ========= ======== ==========================================
name            type                default   unit     meaning
=============== =================== ========= ======== ==========================================
``reflectance`` float or texture    0.5       1        facet albedo rho in [0, 1] (a ``bitmap``
                                                       of the terrain albedo grid in simlunar)
``sigma``       float or texture    0.0       radian   facet slope standard deviation, in
                                                       [0, pi/2); 0 is Lambert
``model``       string              ``full``  --       ``full`` (C1, C2, C3 and the rho^2
                                                       inter-reflection term) or ``qualitative``
                                                       (the A/B form)
=============== =================== ========= ======== ==========================================

A float ``sigma`` keeps the sigma-only factors (C1, C2/k, C3/k', C4) as opaque constants
computed once, so changing it through ``mi.traverse`` reuses the compiled kernels. A texture
``sigma`` (e.g. a ``bitmap`` of per-cell roughness, read with ``eval_1`` at the surface
interaction like the reflectance) computes them per lane with the same formulas, so a constant
texture gives the same image as the float (bit-identical on LLVM). Texture values are checked
to lie in ``[0, pi/2)`` (every ``data``/``value`` parameter of the texture) at load and on
``parameters_changed``.

``mi.traverse`` exposes ``reflectance`` (differentiable) and ``sigma`` (the float or the
texture; not differentiable).
"""

from __future__ import annotations

import math

import numpy as np

from simlunar.render.plugins._common import (
    INV_PI,
    choice,
    local_angles,
    opaque,
    register_plugin,
)

__all__ = ["NAME", "on_factors", "register"]

NAME = "oren_nayar"

_REGISTERED: set[str] = set()


def on_factors(sigma):
    """sigma-only factors of the full / qualitative model: C1, C2 / k, C3 / k', C4."""
    s2 = sigma * sigma
    k = s2 / (s2 + 0.09)
    c1 = 1.0 - 0.5 * s2 / (s2 + 0.33)
    c2k = 0.45 * k
    # C3 = 0.125 k (4 alpha beta / pi^2)^2
    c3k = 0.125 * k * 16.0 * INV_PI**4
    c4 = 0.17 * s2 / (s2 + 0.13)
    return c1, c2k, c3k, c4


def register(mi) -> None:
    """Define and register the plugin for the current variant (idempotent)."""
    register_plugin(mi, NAME, _REGISTERED, _plugin_class)


def _check_sigma(sigma: float) -> None:
    if not (math.isfinite(sigma) and 0.0 <= sigma < math.pi / 2):
        raise ValueError(f"oren_nayar: sigma must be in [0, pi/2) radians, got {sigma}")


def _check_sigma_texture(mi, tex) -> None:
    """Every float parameter of a sigma texture (``data``, ``value``) in [0, pi/2)."""
    params = mi.traverse(tex)
    for key in params.keys():
        if not (key == "data" or key == "value" or key.endswith((".data", ".value"))):
            continue
        v = np.asarray(params[key], dtype=np.float64).ravel()
        if v.size and (not np.isfinite(v).all() or v.min() < 0.0 or v.max() >= math.pi / 2):
            raise ValueError(
                f"oren_nayar: sigma texture values must be finite and in [0, pi/2) "
                f"radians; {key} has range [{np.nanmin(v):.6g}, {np.nanmax(v):.6g}]"
            )


# The kernels below take drjit arrays and import drjit (heavy, optional) when traced, like the
# plugin class: importing this module never imports Mitsuba or drjit.


def _alpha_beta(cos_i, cos_o, sin_i, sin_o):
    """sin and cos of alpha = max(theta_i, theta_o) and beta = min(theta_i, theta_o), tan(beta)."""
    import drjit as dr

    sin_a = dr.maximum(sin_i, sin_o)
    sin_b = dr.minimum(sin_i, sin_o)
    cos_a = dr.minimum(cos_i, cos_o)
    cos_b = dr.maximum(cos_i, cos_o)
    tan_b = sin_b / dr.maximum(cos_b, 1e-7)
    return sin_a, sin_b, cos_a, cos_b, tan_b


def _full_terms(factors, cdp, sin_a, sin_b, cos_a, cos_b, tan_b):
    """The full model's factors of rho and of rho^2 (``f = (rho g1 + rho^2 g2) / pi``)."""
    import drjit as dr

    c1, c2k, c3k, c4 = factors
    alpha = dr.safe_acos(cos_a)
    beta = dr.safe_acos(cos_b)
    two_b_pi = 2.0 * INV_PI * beta
    c2 = c2k * dr.select(cdp >= 0, sin_a, sin_a - two_b_pi * two_b_pi * two_b_pi)
    q = alpha * beta
    # tan((alpha + beta)/2) = (sin a + sin b) / (cos a + cos b): no tan needed
    tan_mid = (sin_a + sin_b) / dr.maximum(cos_a + cos_b, 1e-7)
    g1 = c1 + cdp * c2 * tan_b + (1.0 - dr.abs(cdp)) * (c3k * q * q) * tan_mid
    g2 = c4 * (1.0 - cdp * two_b_pi * two_b_pi)
    return g1, g2


def _plugin_class(mi, base: type) -> type:
    """The plugin class for the current variant, a subclass of ``base`` (cosine sampling)."""
    import drjit as dr  # heavy and optional: only once a Mitsuba variant is set

    class OrenNayarPlugin(base):
        """Oren-Nayar (1994) BRDF; see :func:`simlunar.render.reference.oren_nayar`."""

        def __init__(self, props):
            super().__init__(props)
            self.reflectance = props.get_texture("reflectance", 0.5)
            self.model = choice(props, "model", "full", ("full", "qualitative"), NAME)
            raw = props.get("sigma", 0.0)
            if isinstance(raw, mi.Texture):
                _check_sigma_texture(mi, raw)
                self.sigma_texture = raw
                self.sigma = None
                return
            self.sigma_texture = None
            sigma = float(raw)
            _check_sigma(sigma)
            self.sigma = opaque(mi, sigma)
            self._constants()

        def _f(self, si, wo, active):
            rho = self.reflectance.eval(si, active)
            if self.sigma_texture is None:
                factors = self.c1, self.c2k, self.c3k, self.c4
            else:
                factors = on_factors(self.sigma_texture.eval_1(si, active))
            cos_i, cos_o, sin_i, sin_o, cdp = local_angles(si, wo)
            sin_a, sin_b, cos_a, cos_b, tan_b = _alpha_beta(cos_i, cos_o, sin_i, sin_o)
            if self.model == "qualitative":
                c1, c2k, _, _ = factors
                g = c1 + c2k * dr.maximum(cdp, 0.0) * sin_a * tan_b
                return rho * (INV_PI * g)
            g1, g2 = _full_terms(factors, cdp, sin_a, sin_b, cos_a, cos_b, tan_b)
            return INV_PI * (rho * g1 + rho * rho * g2)

        def _constants(self):
            """sigma-only factors, computed once (opaque: a new sigma reuses the kernels)."""
            self.c1, self.c2k, self.c3k, self.c4 = on_factors(self.sigma)
            for name in ("sigma", "c1", "c2k", "c3k", "c4"):
                value = getattr(self, name)
                dr.eval(value)
                dr.make_opaque(value)

        def traverse(self, callback):
            callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)
            if self.sigma_texture is None:
                callback.put("sigma", self.sigma, mi.ParamFlags.NonDifferentiable)
            else:
                callback.put("sigma", self.sigma_texture, mi.ParamFlags.NonDifferentiable)

        def parameters_changed(self, keys):
            if self.sigma_texture is not None:
                _check_sigma_texture(mi, self.sigma_texture)
                return
            _check_sigma(float(self.sigma[0]))
            self._constants()

        def to_string(self):
            sigma = (
                f"{float(self.sigma[0]):.6g}" if self.sigma_texture is None else self.sigma_texture
            )
            return f"OrenNayar[sigma={sigma}, model={self.model}, reflectance={self.reflectance}]"

    return OrenNayarPlugin
