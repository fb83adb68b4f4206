"""Mitsuba BSDF plugins ``oren_nayar`` and ``hapke`` (Python, JIT-compiled by Dr.Jit).

The plugin classes subclass ``mi.BSDF``, which only exists once the Mitsuba variant is set, so
they are defined inside :func:`_register`, run by :mod:`simlunar.render.backend` right after
``mi.set_variant``. Importing this module never imports Mitsuba.

Both plugins evaluate exactly the formulas of :mod:`simlunar.render.reference` (the tests
compare them on an angle grid) in Mitsuba's local shading frame (z = shading normal,
``si.wi`` towards the previous vertex, ``wo`` the other direction). Like every Mitsuba BSDF,
``eval`` returns ``f * cos(theta_o)``. Sampling is cosine-weighted over the upper hemisphere.
Model constants are kept opaque (``dr.make_opaque``), so changing them through
``mi.traverse`` re-uses the compiled kernels.

Plugin parameters
-----------------
``oren_nayar``: ``reflectance`` (texture or float, the facet albedo rho), ``sigma`` (float or
texture, radians), ``model`` (string, ``"full"`` or ``"qualitative"``). A float ``sigma`` keeps
the sigma-only factors as opaque constants computed once (one kernel for any sigma); a
texture ``sigma`` (e.g. a ``bitmap`` of per-cell roughness, read with ``eval_1`` at the
surface interaction like the reflectance) computes them per lane with the same formulas,
so a constant texture gives the same image as the float. Texture values are checked to lie
in ``[0, pi/2)`` (every ``data``/``value`` parameter of the texture) at load and on
``parameters_changed``.

``hapke``: ``reflectance`` (texture or float), ``albedo_mode`` (``"normal"``: the reflectance is
the normal albedo and the single-scattering albedo w is derived per point so the normal
albedo matches; ``"w"``: the reflectance *is* w), ``b``, ``c``, ``B0``, ``h``,
``theta_bar`` (radians).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from simlunar.render import backend
from simlunar.render import reference as ref
from simlunar.render.materials import HapkeBSDF, LambertBSDF, OrenNayarBSDF

__all__ = ["HAPKE_TABLE_SIZE", "bsdf_dict"]

#: entries of the normal albedo -> w lookup table of the ``hapke`` plugin (albedo in [0, 1])
HAPKE_TABLE_SIZE = 1024


def _texture(reflectance: Any) -> Any:
    if isinstance(reflectance, (int, float, np.floating, np.integer)):
        v = float(reflectance)
        if not (math.isfinite(v) and 0.0 <= v <= 1.0):
            raise ValueError(f"reflectance must be in [0, 1], got {reflectance!r}")
        return v
    return reflectance


def bsdf_dict(spec: LambertBSDF | OrenNayarBSDF | HapkeBSDF, reflectance: Any = 0.5) -> dict:
    """Mitsuba ``load_dict`` entry for a BSDF spec.

    Parameters
    ----------
    spec : LambertBSDF, OrenNayarBSDF or HapkeBSDF
        From :func:`simlunar.render.materials.make_bsdf`.
    reflectance : float, dict or mitsuba Texture
        The albedo: a constant in [0, 1], a Mitsuba texture dict (e.g. a ``bitmap`` of the
        terrain albedo grid) or a loaded texture. Lambert: diffuse reflectance;
        Oren-Nayar: facet albedo; Hapke: normal albedo (ignored when ``spec.w`` is set).
        An ``OrenNayarBSDF`` with a ``sigma_map`` gets that grid as a ``bitmap`` ``sigma``
        texture with the same addressing as a grid albedo (texel (r, c) at terrain vertex
        (r, c), nearest filter: :func:`simlunar.render.mesh.grid_texture`).

    Returns
    -------
    dict
        ``{"type": "diffuse" | "oren_nayar" | "hapke", ...}``; the plugins are registered by
        :func:`simlunar.render.backend.init`.
    """
    tex = _texture(reflectance)
    if isinstance(spec, LambertBSDF):
        return {"type": "diffuse", "reflectance": tex}
    if isinstance(spec, OrenNayarBSDF):
        sigma: Any = spec.sigma
        if spec.sigma_map is not None:
            from simlunar.render.mesh import grid_texture

            sigma = grid_texture(spec.sigma_map)
        return {"type": "oren_nayar", "reflectance": tex, "sigma": sigma, "model": spec.model}
    if isinstance(spec, HapkeBSDF):
        d = {
            "type": "hapke",
            "b": spec.b,
            "c": spec.c,
            "B0": spec.B0,
            "h": spec.h,
            "theta_bar": spec.theta_bar,
        }
        if spec.w is None:
            d.update(reflectance=tex, albedo_mode="normal")
        else:
            d.update(reflectance=spec.w, albedo_mode="w")
        return d
    raise ValueError(
        f"bsdf must be a LambertBSDF, OrenNayarBSDF or HapkeBSDF spec, got {type(spec).__name__}"
    )


_REGISTERED: set[str] = set()


def _register(mi) -> None:
    """Define and register the plugin classes for the current variant (idempotent)."""
    variant = mi.variant()
    if variant in _REGISTERED:
        return
    import drjit as dr

    inv_pi = 1.0 / math.pi
    flags_diffuse = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
    flags_glossy = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide

    def _scalar(props, key, default):
        return float(props.get(key, default))

    def _opaque(value) -> Any:
        v = mi.Float(value)
        dr.make_opaque(v)
        return v

    def _local(si, wo):
        """cos_i, cos_o, sin_i, sin_o, cos(phi_i - phi_o) in the local frame."""
        wi = si.wi
        cos_i, cos_o = wi.z, wo.z
        sin_i = dr.safe_sqrt(dr.fma(-cos_i, cos_i, 1.0))
        sin_o = dr.safe_sqrt(dr.fma(-cos_o, cos_o, 1.0))
        # cos of the azimuth difference = (xy . xy) / (sin sin); 0 where an azimuth is
        # undefined (direction along the normal), where every model is independent of it
        ss = sin_i * sin_o
        cdp = dr.select(ss > 1e-7, (wi.x * wo.x + wi.y * wo.y) / ss, 0.0)
        return cos_i, cos_o, sin_i, sin_o, dr.clip(cdp, -1.0, 1.0)

    class _CosineBSDF(mi.BSDF):
        """Shared cosine-hemisphere sampling; subclasses define ``_f`` (BRDF, no cosine)."""

        flags = flags_diffuse
        lobe = mi.BSDFFlags.DiffuseReflection

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.m_components = [self.flags]
            self.m_flags = self.flags

        def _enabled(self, ctx) -> bool:
            return ctx.is_enabled(self.lobe, 0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            cos_i = mi.Frame3f.cos_theta(si.wi)
            bs = dr.zeros(mi.BSDFSample3f)
            if not self._enabled(ctx):
                return bs, mi.Color3f(0.0)
            active = mi.Bool(active) & (cos_i > 0)
            bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+self.lobe)
            bs.sampled_component = mi.UInt32(0)
            active &= bs.pdf > 0
            # f cos / pdf = f * pi for cosine sampling
            value = self._f(si, bs.wo, active) * math.pi
            bs.pdf = dr.select(active, bs.pdf, 0.0)
            return bs, dr.select(active, value, 0.0)

        def eval(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return mi.Color3f(0.0)
            cos_i = mi.Frame3f.cos_theta(si.wi)
            cos_o = mi.Frame3f.cos_theta(wo)
            active = mi.Bool(active) & (cos_i > 0) & (cos_o > 0)
            return dr.select(active, self._f(si, wo, active) * cos_o, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return mi.Float(0.0)
            cos_i = mi.Frame3f.cos_theta(si.wi)
            cos_o = mi.Frame3f.cos_theta(wo)
            ok = mi.Bool(active) & (cos_i > 0) & (cos_o > 0)
            return dr.select(ok, mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return mi.Color3f(0.0), mi.Float(0.0)
            cos_i = mi.Frame3f.cos_theta(si.wi)
            cos_o = mi.Frame3f.cos_theta(wo)
            ok = mi.Bool(active) & (cos_i > 0) & (cos_o > 0)
            value = dr.select(ok, self._f(si, wo, ok) * cos_o, 0.0)
            return value, dr.select(ok, cos_o * inv_pi, 0.0)

    def _on_factors(sigma):
        """sigma-only factors of the full / qualitative model: C1, C2 / k, C3 / k', C4."""
        s2 = sigma * sigma
        k = s2 / (s2 + 0.09)
        c1 = 1.0 - 0.5 * s2 / (s2 + 0.33)
        c2k = 0.45 * k
        # C3 = 0.125 k (4 alpha beta / pi^2)^2
        c3k = 0.125 * k * 16.0 * inv_pi**4
        c4 = 0.17 * s2 / (s2 + 0.13)
        return c1, c2k, c3k, c4

    def _check_sigma_texture(tex) -> None:
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

    class OrenNayarPlugin(_CosineBSDF):
        """Oren-Nayar (1994) BRDF; see :func:`simlunar.render.reference.oren_nayar`."""

        def __init__(self, props):
            super().__init__(props)
            self.reflectance = props.get_texture("reflectance", 0.5)
            model = str(props.get("model", "full"))
            if model not in ("full", "qualitative"):
                raise ValueError(f"oren_nayar: model must be full or qualitative, got {model!r}")
            self.model = model
            raw = props.get("sigma", 0.0)
            if isinstance(raw, mi.Texture):
                _check_sigma_texture(raw)
                self.sigma_texture = raw
                self.sigma = None
                return
            self.sigma_texture = None
            sigma = float(raw)
            if not (math.isfinite(sigma) and 0.0 <= sigma < math.pi / 2):
                raise ValueError(f"oren_nayar: sigma must be in [0, pi/2) radians, got {sigma}")
            self.sigma = _opaque(sigma)
            self._constants()

        def _f(self, si, wo, active):
            rho = self.reflectance.eval(si, active)
            if self.sigma_texture is None:
                c1, c2k, c3k, c4 = self.c1, self.c2k, self.c3k, self.c4
            else:
                c1, c2k, c3k, c4 = _on_factors(self.sigma_texture.eval_1(si, active))
            cos_i, cos_o, sin_i, sin_o, cdp = _local(si, wo)
            # alpha = max(theta_i, theta_o), beta = min(theta_i, theta_o)
            sin_a = dr.maximum(sin_i, sin_o)
            sin_b = dr.minimum(sin_i, sin_o)
            cos_a = dr.minimum(cos_i, cos_o)
            cos_b = dr.maximum(cos_i, cos_o)
            tan_b = sin_b / dr.maximum(cos_b, 1e-7)
            if self.model == "qualitative":
                g = c1 + c2k * dr.maximum(cdp, 0.0) * sin_a * tan_b
                return rho * (inv_pi * g)
            alpha = dr.safe_acos(cos_a)
            beta = dr.safe_acos(cos_b)
            two_b_pi = 2.0 * inv_pi * beta
            c2 = c2k * dr.select(cdp >= 0, sin_a, sin_a - two_b_pi * two_b_pi * two_b_pi)
            q = alpha * beta
            # tan((alpha + beta)/2) = (sin a + sin b) / (cos a + cos b): no tan needed
            tan_mid = (sin_a + sin_b) / dr.maximum(cos_a + cos_b, 1e-7)
            g1 = c1 + cdp * c2 * tan_b + (1.0 - dr.abs(cdp)) * (c3k * q * q) * tan_mid
            g2 = c4 * (1.0 - cdp * two_b_pi * two_b_pi)
            return inv_pi * (rho * g1 + rho * rho * g2)

        def _constants(self):
            """sigma-only factors, computed once (opaque: a new sigma reuses the kernels)."""
            self.c1, self.c2k, self.c3k, self.c4 = _on_factors(self.sigma)
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
                _check_sigma_texture(self.sigma_texture)
                return
            s = float(self.sigma[0])
            if not (math.isfinite(s) and 0.0 <= s < math.pi / 2):
                raise ValueError(f"oren_nayar: sigma must be in [0, pi/2) radians, got {s}")
            self._constants()

        def to_string(self):
            sigma = (
                f"{float(self.sigma[0]):.6g}" if self.sigma_texture is None else self.sigma_texture
            )
            return f"OrenNayar[sigma={sigma}, model={self.model}, reflectance={self.reflectance}]"

    class HapkePlugin(_CosineBSDF):
        """Hapke BRDF; see :func:`simlunar.render.reference.hapke`."""

        flags = flags_glossy
        lobe = mi.BSDFFlags.GlossyReflection
        _keys = ("b", "c", "B0", "h", "theta_bar")

        def __init__(self, props):
            super().__init__(props)
            self.reflectance = props.get_texture("reflectance", 0.12)
            mode = str(props.get("albedo_mode", "normal"))
            if mode not in ("normal", "w"):
                raise ValueError(f"hapke: albedo_mode must be normal or w, got {mode!r}")
            self.albedo_mode = mode
            d = ref.LUNAR_HAPKE
            vals = {k: _scalar(props, k, getattr(d, k)) for k in self._keys}
            HapkeBSDF(**vals)  # validates and names the offending field
            for k, v in vals.items():
                setattr(self, k, _opaque(v))
            self._update_table()

        def _params(self) -> dict:
            return {k: float(getattr(self, k)[0]) for k in self._keys}

        def _update_table(self):
            p = self._params()
            HapkeBSDF(**p)
            albedo = np.linspace(0.0, 1.0, HAPKE_TABLE_SIZE)
            self.w_table = mi.Float(ref.hapke_w_from_normal_albedo(albedo, **p).astype(np.float32))

        def _w(self, si, active):
            a = self.reflectance.eval(si, active)
            if self.albedo_mode == "w":
                return dr.clip(a, 0.0, 1.0)
            n = HAPKE_TABLE_SIZE
            out = []
            for ch in range(3):
                t = dr.clip(a[ch], 0.0, 1.0) * (n - 1)
                i0 = mi.UInt32(dr.minimum(dr.floor(t), n - 2))
                fr = t - mi.Float(i0)
                w0 = dr.gather(mi.Float, self.w_table, i0, active)
                w1 = dr.gather(mi.Float, self.w_table, i0 + 1, active)
                out.append(dr.fma(fr, w1 - w0, w0))
            return mi.Color3f(out[0], out[1], out[2])

        @staticmethod
        def _h(x, w):
            x = dr.maximum(x, 1e-6)
            gamma = dr.sqrt(dr.maximum(1.0 - w, 0.0))
            r0 = (1.0 - gamma) / (1.0 + gamma)
            return dr.rcp(1.0 - w * x * (r0 + (1.0 - 2.0 * r0 * x) * 0.5 * dr.log((1.0 + x) / x)))

        def _f(self, si, wo, active):
            w = self._w(si, active)
            mu0, mu, si_, se, cpsi = _local(si, wo)
            mu0 = dr.clip(mu0, 1e-6, 1.0)
            mu = dr.clip(mu, 1e-6, 1.0)
            si_ = dr.maximum(si_, 1e-6)
            se = dr.maximum(se, 1e-6)
            # macroscopic roughness (Hapke 1984); theta_bar = 0 is approached, not special-cased
            tb = dr.maximum(dr.tan(self.theta_bar), 1e-4)
            cot_tb = dr.rcp(tb)
            chi = dr.rsqrt(1.0 + math.pi * tb * tb)
            cot_i = mu0 / si_
            cot_e = mu / se
            e1i = dr.exp(-2.0 * inv_pi * cot_tb * cot_i)
            e1e = dr.exp(-2.0 * inv_pi * cot_tb * cot_e)
            e2i = dr.exp(-inv_pi * cot_tb * cot_tb * cot_i * cot_i)
            e2e = dr.exp(-inv_pi * cot_tb * cot_tb * cot_e * cot_e)
            eta_i = chi * (mu0 + si_ * tb * e2i / (2.0 - e1i))
            eta_e = chi * (mu + se * tb * e2e / (2.0 - e1e))
            psi = dr.safe_acos(cpsi)
            s2 = dr.square(dr.sin(0.5 * psi))
            fpsi = dr.exp(-2.0 * dr.tan(0.5 * dr.minimum(psi, math.pi - 1e-3)))
            first = mu0 >= mu  # i <= e
            d = dr.select(first, 2.0 - e1e - psi * inv_pi * e1i, 2.0 - e1i - psi * inv_pi * e1e)
            mu0e = chi * (
                mu0 + si_ * tb * dr.select(first, cpsi * e2e + s2 * e2i, e2i - s2 * e2e) / d
            )
            mue = chi * (mu + se * tb * dr.select(first, e2e - s2 * e2i, cpsi * e2i + s2 * e2e) / d)
            ratio = dr.select(first, mu0 / eta_i, mu / eta_e)
            shadow = mue / eta_e * mu0 / eta_i * chi / (1.0 - fpsi + fpsi * chi * ratio)
            # phase function and opposition surge (phase angle g between wi and wo)
            cos_g = dr.clip(dr.dot(si.wi, wo), -1.0, 1.0)
            b, c = self.b, self.c
            b2 = b * b
            back = (1.0 - b2) / dr.power(1.0 - 2.0 * b * cos_g + b2, 1.5)
            fwd = (1.0 - b2) / dr.power(1.0 + 2.0 * b * cos_g + b2, 1.5)
            p = 0.5 * (1.0 + c) * back + 0.5 * (1.0 - c) * fwd
            # |wi - wo| / |wi + wo| = tan(g/2), accurate near g = 0 where the surge peaks
            tan_half_g = dr.norm(si.wi - wo) / dr.maximum(dr.norm(si.wi + wo), 1e-7)
            surge = 1.0 + self.B0 / (1.0 + tan_half_g / self.h)
            multiple = self._h(mu0e, w) * self._h(mue, w) - 1.0
            scale = 0.25 * inv_pi * mu0e / (mu0e + mue) * shadow / mu0
            return w * scale * (p * surge + multiple)

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

    mi.register_bsdf("oren_nayar", lambda props: OrenNayarPlugin(props))
    mi.register_bsdf("hapke", lambda props: HapkePlugin(props))
    _REGISTERED.add(variant)


backend.register_plugin_hook(_register)
