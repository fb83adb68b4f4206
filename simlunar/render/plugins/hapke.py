"""Mitsuba BSDF plugin ``hapke``: Hapke's regolith BRDF.

Evaluates exactly the formulas of :func:`simlunar.render.reference.hapke` (the tests compare
them on an angle grid) in Mitsuba's local shading frame; ``eval`` returns ``f * cos(theta_o)``.
Double Henyey-Greenstein phase function, shadow-hiding opposition surge
``B0 / (1 + tan(g/2) / h)`` on the single scattering, coherent-backscatter opposition surge
``1 + B_C0 B_C(g)`` on the whole reflectance (Hapke 2002 eq. 32;
:func:`simlunar.render.reference.hapke_coherent_backscatter`), Hapke (2002) H functions for
multiple scattering, Hapke (1984) macroscopic roughness. Sampling is cosine-weighted over the
upper hemisphere. Lobe: glossy reflection, front side only.

Parameters
----------

=============== ================= ============= ======== ===========================================
name            type              default       unit     meaning
=============== ================= ============= ======== ===========================================
``reflectance`` float or texture  0.12          1        normal albedo in [0, 1] (``albedo_mode``
                                                         ``normal``) or the single-scattering
                                                         albedo w (``albedo_mode`` ``w``)
``albedo_mode`` string            ``normal``    --       ``normal``: w is derived per point from
                                                         a table (:data:`HAPKE_TABLE_SIZE`
                                                         entries, linear interpolation) so that
                                                         the Hapke normal albedo equals the
                                                         reflectance; ``w``: the reflectance is w
``b``           float             0.26          1        Henyey-Greenstein lobe width, [0, 1)
``c``           float             0.08          1        backscatter lobe weight (1 + c) / 2,
                                                         [-1, 1]
``B0``          float             1.0           1        shadow-hiding opposition surge
                                                         amplitude B_S0, >= 0
``h``           float             0.07          1        shadow-hiding opposition surge
                                                         angular width h_S, > 0
``theta_bar``   float             0.41289       radian   mean macroscopic slope (23.657 deg),
                                                         [0, pi/2)
``B_C0``        float             0.0           1        coherent-backscatter opposition
                                                         surge amplitude, >= 0 (0: none)
``h_C``         float             0.03          1        coherent-backscatter opposition
                                                         surge angular width, > 0
=============== ================= ============= ======== ===========================================

Defaults are :data:`simlunar.render.reference.LUNAR_HAPKE`. The scalar parameters are opaque
constants: changing them through ``mi.traverse`` reuses the compiled kernels (the albedo table
is rebuilt on ``parameters_changed``). ``mi.traverse`` exposes ``reflectance``
(differentiable) and ``b``, ``c``, ``B0``, ``h``, ``theta_bar``, ``B_C0``, ``h_C`` (not
differentiable).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from simlunar.render import reference as ref
from simlunar.render.materials import HapkeBSDF
from simlunar.render.plugins._common import (
    INV_PI,
    choice,
    local_angles,
    opaque,
    register_plugin,
    scalar,
)

__all__ = ["HAPKE_TABLE_SIZE", "NAME", "register"]

NAME = "hapke"

#: entries of the normal albedo -> w lookup table (albedo in [0, 1])
HAPKE_TABLE_SIZE = 1024

_REGISTERED: set[str] = set()


def register(mi) -> None:
    """Define and register the plugin for the current variant (idempotent)."""
    register_plugin(mi, NAME, _REGISTERED, _plugin_class)


# The kernels below take drjit arrays and import drjit (heavy, optional) when traced, like the
# plugin classes: importing this module never imports Mitsuba or drjit.


def _w_from_table(mi, w_table, albedo, active):
    """Per-channel w of a normal ``albedo`` (Color3f): linear interpolation in ``w_table``."""
    import drjit as dr

    n = HAPKE_TABLE_SIZE
    out = []
    for ch in range(3):
        t = dr.clip(albedo[ch], 0.0, 1.0) * (n - 1)
        i0 = mi.UInt32(dr.minimum(dr.floor(t), n - 2))
        fr = t - mi.Float(i0)
        w0 = dr.gather(mi.Float, w_table, i0, active)
        w1 = dr.gather(mi.Float, w_table, i0 + 1, active)
        out.append(dr.fma(fr, w1 - w0, w0))
    return mi.Color3f(out[0], out[1], out[2])


def _h(x, w):
    """Hapke's (2002) H function (:func:`simlunar.render.reference.hapke_h_function`)."""
    import drjit as dr

    x = dr.maximum(x, 1e-6)
    gamma = dr.sqrt(dr.maximum(1.0 - w, 0.0))
    r0 = (1.0 - gamma) / (1.0 + gamma)
    return dr.rcp(1.0 - w * x * (r0 + (1.0 - 2.0 * r0 * x) * 0.5 * dr.log((1.0 + x) / x)))


def _roughness(mu0, mu, sin_i, sin_e, cpsi, theta_bar):
    """Hapke (1984) macroscopic roughness: ``(mu0e, mue, shadowing)``.

    ``mu0``, ``mu`` are the cosines of incidence and emission (clipped to [1e-6, 1]), ``sin_i``,
    ``sin_e`` their sines, ``cpsi`` the cosine of the azimuth difference. theta_bar = 0 is
    approached, not special-cased.
    """
    import drjit as dr

    inv_pi = INV_PI
    sin_i = dr.maximum(sin_i, 1e-6)
    sin_e = dr.maximum(sin_e, 1e-6)
    tb = dr.maximum(dr.tan(theta_bar), 1e-4)
    cot_tb = dr.rcp(tb)
    chi = dr.rsqrt(1.0 + math.pi * tb * tb)
    cot_i = mu0 / sin_i
    cot_e = mu / sin_e
    e1i = dr.exp(-2.0 * inv_pi * cot_tb * cot_i)
    e1e = dr.exp(-2.0 * inv_pi * cot_tb * cot_e)
    e2i = dr.exp(-inv_pi * cot_tb * cot_tb * cot_i * cot_i)
    e2e = dr.exp(-inv_pi * cot_tb * cot_tb * cot_e * cot_e)
    eta_i = chi * (mu0 + sin_i * tb * e2i / (2.0 - e1i))
    eta_e = chi * (mu + sin_e * tb * e2e / (2.0 - e1e))
    psi = dr.safe_acos(cpsi)
    s2 = dr.square(dr.sin(0.5 * psi))
    fpsi = dr.exp(-2.0 * dr.tan(0.5 * dr.minimum(psi, math.pi - 1e-3)))
    first = mu0 >= mu  # i <= e
    d = dr.select(first, 2.0 - e1e - psi * inv_pi * e1i, 2.0 - e1i - psi * inv_pi * e1e)
    mu0e = chi * (mu0 + sin_i * tb * dr.select(first, cpsi * e2e + s2 * e2i, e2i - s2 * e2e) / d)
    mue = chi * (mu + sin_e * tb * dr.select(first, e2e - s2 * e2i, cpsi * e2i + s2 * e2e) / d)
    ratio = dr.select(first, mu0 / eta_i, mu / eta_e)
    shadow = mue / eta_e * mu0 / eta_i * chi / (1.0 - fpsi + fpsi * chi * ratio)
    return mu0e, mue, shadow


def _coherent(tan_half_g, h_c):
    """Hapke's coherent-backscatter function ``B_C`` (:func:`simlunar.render.reference.
    hapke_coherent_backscatter`); ``(1 - exp(-x)) / x`` by its series below ``x = 0.01``
    (float32 cancellation above, series truncation below: both under 1e-5 relative)."""
    import drjit as dr

    x = tan_half_g / h_c
    series = 1.0 - x * (0.5 - x * (1.0 / 6.0 - x / 24.0))
    ratio = dr.select(x < 0.01, series, (1.0 - dr.exp(-x)) / dr.maximum(x, 0.01))
    return (1.0 + ratio) / (2.0 * dr.square(1.0 + x))


def _phase(cos_g, b, c):
    """Double Henyey-Greenstein phase function (:func:`simlunar.render.reference.hapke_phase`)."""
    import drjit as dr

    b2 = b * b
    back = (1.0 - b2) / dr.power(1.0 - 2.0 * b * cos_g + b2, 1.5)
    fwd = (1.0 - b2) / dr.power(1.0 + 2.0 * b * cos_g + b2, 1.5)
    return 0.5 * (1.0 + c) * back + 0.5 * (1.0 - c) * fwd


def _plugin_class(mi, base: type) -> type:
    """The plugin class for the current variant, a subclass of ``base`` (cosine sampling)."""
    import drjit as dr  # heavy and optional: only once a Mitsuba variant is set

    class HapkePlugin(base):
        """Hapke BRDF; see :func:`simlunar.render.reference.hapke`."""

        flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
        lobe = mi.BSDFFlags.GlossyReflection
        _keys = ("b", "c", "B0", "h", "theta_bar", "B_C0", "h_C")

        def __init__(self, props):
            super().__init__(props)
            self.reflectance = props.get_texture("reflectance", 0.12)
            self.albedo_mode = choice(props, "albedo_mode", "normal", ("normal", "w"), NAME)
            d = ref.LUNAR_HAPKE
            vals = {k: scalar(props, k, getattr(d, k)) for k in self._keys}
            HapkeBSDF(**vals)  # validates and names the offending field
            for k, v in vals.items():
                setattr(self, k, opaque(mi, v))
            self._update_table()

        def _params(self) -> dict:
            return {k: float(getattr(self, k)[0]) for k in self._keys}

        def _update_table(self):
            p = self._params()
            HapkeBSDF(**p)
            albedo = np.linspace(0.0, 1.0, HAPKE_TABLE_SIZE)
            w = ref.hapke_w_from_normal_albedo(albedo, replace(ref.LUNAR_HAPKE, **p))
            self.w_table = mi.Float(w.astype(np.float32))

        def _w(self, si, active):
            a = self.reflectance.eval(si, active)
            if self.albedo_mode == "w":
                return dr.clip(a, 0.0, 1.0)
            return _w_from_table(mi, self.w_table, a, active)

        def _f(self, si, wo, active):
            w = self._w(si, active)
            mu0, mu, sin_i, sin_e, cpsi = local_angles(si, wo)
            mu0 = dr.clip(mu0, 1e-6, 1.0)
            mu = dr.clip(mu, 1e-6, 1.0)
            mu0e, mue, shadow = _roughness(mu0, mu, sin_i, sin_e, cpsi, self.theta_bar)
            # phase function and opposition surge (phase angle g between wi and wo)
            cos_g = dr.clip(dr.dot(si.wi, wo), -1.0, 1.0)
            p = _phase(cos_g, self.b, self.c)
            # |wi - wo| / |wi + wo| = tan(g/2), accurate near g = 0 where the surge peaks
            tan_half_g = dr.norm(si.wi - wo) / dr.maximum(dr.norm(si.wi + wo), 1e-7)
            surge = 1.0 + self.B0 / (1.0 + tan_half_g / self.h)
            multiple = _h(mu0e, w) * _h(mue, w) - 1.0
            scale = 0.25 * INV_PI * mu0e / (mu0e + mue) * shadow / mu0
            coherent = 1.0 + self.B_C0 * _coherent(tan_half_g, self.h_C)
            return w * scale * (p * surge + multiple) * coherent

        def traverse(self, callback):
            callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)
            for k in self._keys:
                callback.put(k, getattr(self, k), mi.ParamFlags.NonDifferentiable)

        def parameters_changed(self, keys):
            self._update_table()
            for k in self._keys:
                dr.make_opaque(getattr(self, k))

        def to_string(self):
            p = ", ".join(f"{k}={v:.6g}" for k, v in self._params().items())
            return f"Hapke[{p}, albedo_mode={self.albedo_mode}, reflectance={self.reflectance}]"

    return HapkePlugin
