"""Configuration of the landing questions a LIDAR study scores: hazard detection
(:class:`HazardCfg`) and safe-site choice (:class:`SafeSiteCfg`) (split from
:mod:`simlunar.config.lidar`, which re-exports both)."""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator, Field, PositiveInt

from simlunar.config.fields import Deg, Metres, _Model

__all__ = ["HazardCfg", "LandingCfg", "MedianWindowPx", "SafeSiteCfg", "SlopeBaselinePx"]


def _odd(v: int) -> int:
    """A median window's side: odd, so that the window is centred on its pixel."""
    if v % 2 == 0:
        raise ValueError(f"must be odd (a centred window), got {v}")
    return v


#: side of the median neighbourhood a hazard's relief is measured against (odd, 3 .. 255 px)
MedianWindowPx = Annotated[
    int,
    Field(ge=3, le=255, description="median neighbourhood side (odd, px)"),
    AfterValidator(_odd),
]
#: half-baseline of a hazard's slope (1 .. 64 px)
SlopeBaselinePx = Annotated[PositiveInt, Field(le=64, description="slope half-baseline (px)")]


class HazardCfg(_Model):
    """Landing hazards scored as detection precision / recall
    (:class:`simlunar.metrics.hazard.HazardOptions`)."""

    slope_deg: Deg = Field(15.0, gt=0, lt=90, description="largest safe slope")
    relief_m: Metres = Field(0.3, gt=0, description="largest safe height above the local median")
    window_px: MedianWindowPx = 15
    baseline_px: SlopeBaselinePx = 2


class SafeSiteCfg(_Model):
    """The landing question (:class:`simlunar.metrics.safe_site.SiteOptions`): is the site
    chosen from the reconstruction truly safe? Thresholds: rocks above 0.3 m (ALHAT), slopes
    above 12 deg (Apollo LM limit as usually quoted: an assumption); docs/lidar.md."""

    slope_deg: Deg = Field(12.0, gt=0, lt=90, description="largest safe slope")
    rock_height_m: Metres = Field(
        0.3, gt=0, description="largest safe height above the local median (rocks)"
    )
    window_px: MedianWindowPx = 15
    baseline_px: SlopeBaselinePx = 2
    semi_axes_m: tuple[float, float] = Field(
        (4.0, 4.0), description="landing ellipse semi-axes along world x and y (m)"
    )
    pitch_m: Metres = Field(8.0, gt=0, description="spacing of the candidate ellipse centres")
    max_hazard_fraction: float = Field(
        0.0, ge=0, lt=1, description="a site is safe with at most this share of hazard pixels"
    )


class LandingCfg(_Model):
    """Landing-site scores per hazard size (:class:`simlunar.metrics.landing.LandingOptions`):
    rock recall / precision per rock height, slope recall / precision across the lander's
    footprint, the false-safe rate of the chosen site, height and slope RMS (docs/landing.md)."""

    rock_heights_m: list[Annotated[Metres, Field(gt=0)]] = Field(
        default_factory=lambda: [0.15, 0.30],
        min_length=1,
        max_length=8,
        description="rock hazard sizes: heights above the footprint's median (m)",
    )
    slope_deg: Deg = Field(5.0, gt=0, lt=90, description="largest safe slope across the footprint")
    footprint_m: Metres = Field(
        4.0, gt=0, description="lander footprint: the slope's baseline and a rock's median window"
    )
    site_radius_m: Metres = Field(4.0, gt=0, description="radius of a candidate landing site")
    site_pitch_m: Metres = Field(8.0, gt=0, description="spacing of the candidate sites")
