"""Pieces shared by simlunar's BSDF plugins: local-frame angles and cosine-hemisphere sampling.

Everything here that touches Mitsuba types is built per variant by a function of ``mi``
(the classes subclass ``mi.BSDF``, which exists only once a variant is set).
"""

from __future__ import annotations

import math
from typing import Any

INV_PI = 1.0 / math.pi

_BASES: dict[str, type] = {}


def scalar(props, key: str, default: float) -> float:
    """A float plugin property with a default."""
    return float(props.get(key, default))


def choice(props, key: str, default: str, valid: tuple[str, ...], plugin: str) -> str:
    """A string plugin property that must be one of ``valid`` (``plugin`` names the error)."""
    value = str(props.get(key, default))
    if value not in valid:
        raise ValueError(f"{plugin}: {key} must be {' or '.join(valid)}, got {value!r}")
    return value


def opaque(mi, value) -> Any:
    """``mi.Float(value)`` made opaque: a new value reuses the compiled kernels."""
    import drjit as dr

    v = mi.Float(value)
    dr.make_opaque(v)
    return v


def register_plugin(mi, name: str, registered: set[str], build) -> None:
    """Register the BSDF class ``build(mi, base)`` as plugin ``name`` for the current variant,
    once; ``base`` is the variant's :func:`cosine_bsdf_base`, which the class subclasses.

    ``registered`` holds the variants the plugin is registered for (one set per plugin).
    """
    variant = mi.variant()
    if variant in registered:
        return
    plugin = build(mi, cosine_bsdf_base(mi))
    mi.register_bsdf(name, lambda props: plugin(props))
    registered.add(variant)


def local_angles(si, wo):
    """cos_i, cos_o, sin_i, sin_o, cos(phi_i - phi_o) in the local frame."""
    import drjit as dr

    wi = si.wi
    cos_i, cos_o = wi.z, wo.z
    sin_i = dr.safe_sqrt(dr.fma(-cos_i, cos_i, 1.0))
    sin_o = dr.safe_sqrt(dr.fma(-cos_o, cos_o, 1.0))
    # cos of the azimuth difference = (xy . xy) / (sin sin); 0 where an azimuth is
    # undefined (direction along the normal), where every model is independent of it
    ss = sin_i * sin_o
    cdp = dr.select(ss > 1e-7, (wi.x * wo.x + wi.y * wo.y) / ss, 0.0)
    return cos_i, cos_o, sin_i, sin_o, dr.clip(cdp, -1.0, 1.0)


def cosine_bsdf_base(mi) -> type:
    """The base class of the plugins for the current variant (built once per variant).

    Cosine-weighted sampling of the upper hemisphere, ``eval`` = ``_f * cos(theta_o)``,
    ``pdf``, ``eval_pdf``; subclasses define ``_f(si, wo, active)`` (the BRDF without the
    cosine) and may override ``flags`` and ``lobe`` (diffuse reflection by default). A
    non-reciprocal BRDF overrides ``_value(ctx, si, wo, active)`` instead, which sees the
    transport mode (in ``Radiance`` mode ``wo`` points to the light and ``si.wi`` to the viewer;
    in ``Importance`` mode, light tracing, the reverse).
    """
    variant = mi.variant()
    if variant in _BASES:
        return _BASES[variant]
    import drjit as dr

    class CosineBSDF(mi.BSDF):
        """Shared cosine-hemisphere sampling; subclasses define ``_f`` (BRDF, no cosine)."""

        flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        lobe = mi.BSDFFlags.DiffuseReflection

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.m_components = [self.flags]
            self.m_flags = self.flags

        def _enabled(self, ctx) -> bool:
            return ctx.is_enabled(self.lobe, 0)

        def _value(self, ctx, si, wo, active):
            """The BRDF (no cosine) in ``ctx``'s transport mode: ``_f`` for a reciprocal model,
            whose value is the same in both modes."""
            return self._f(si, wo, active)

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
            value = self._value(ctx, si, bs.wo, active) * math.pi
            bs.pdf = dr.select(active, bs.pdf, 0.0)
            return bs, dr.select(active, value, 0.0)

        @staticmethod
        def _both_up(si, wo, active):
            """cos(theta_o) and ``active`` where light and viewer are above the surface."""
            cos_i = mi.Frame3f.cos_theta(si.wi)
            cos_o = mi.Frame3f.cos_theta(wo)
            return cos_o, mi.Bool(active) & (cos_i > 0) & (cos_o > 0)

        def eval(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return mi.Color3f(0.0)
            cos_o, active = self._both_up(si, wo, active)
            return dr.select(active, self._value(ctx, si, wo, active) * cos_o, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return mi.Float(0.0)
            _, ok = self._both_up(si, wo, active)
            return dr.select(ok, mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return mi.Color3f(0.0), mi.Float(0.0)
            cos_o, ok = self._both_up(si, wo, active)
            value = dr.select(ok, self._value(ctx, si, wo, ok) * cos_o, 0.0)
            return value, dr.select(ok, cos_o * INV_PI, 0.0)

    _BASES[variant] = CosineBSDF
    return CosineBSDF
