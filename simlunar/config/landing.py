"""Configuration of the landing questions a LIDAR study scores: hazard detection
(:class:`HazardCfg`) and safe-site choice (:class:`SafeSiteCfg`) (split from
:mod:`simlunar.config.lidar`, which re-exports both)."""

from __future__ import annotations

from pydantic import Field, PositiveInt, field_validator

from simlunar.config.fields import Deg, Metres, _Model

__all__ = ["HazardCfg", "SafeSiteCfg"]


class HazardCfg(_Model):
    """Landing hazards scored as detection precision / recall
    (:class:`simlunar.metrics.hazard.HazardOptions`)."""

    slope_deg: Deg = Field(15.0, gt=0, lt=90, description="largest safe slope")
    relief_m: Metres = Field(0.3, gt=0, description="largest safe height above the local median")
    window_px: int = Field(15, ge=3, le=255, description="median neighbourhood side (odd, px)")
    baseline_px: PositiveInt = Field(2, le=64, description="slope half-baseline (px)")

    @field_validator("window_px")
    @classmethod
    def _odd(cls, v: int) -> int:
        if v % 2 == 0:
            raise ValueError(f"must be odd (a centred window), got {v}")
        return v


class SafeSiteCfg(_Model):
    """The landing question (:class:`simlunar.metrics.safe_site.SiteOptions`): is the site
    chosen from the reconstruction truly safe? Thresholds: rocks above 0.3 m (ALHAT), slopes
    above 12 deg (Apollo LM limit as usually quoted: an assumption); docs/lidar.md."""

    slope_deg: Deg = Field(12.0, gt=0, lt=90, description="largest safe slope")
    rock_height_m: Metres = Field(
        0.3, gt=0, description="largest safe height above the local median (rocks)"
    )
    window_px: int = Field(15, ge=3, le=255, description="median neighbourhood side (odd, px)")
    baseline_px: PositiveInt = Field(2, le=64, description="slope half-baseline (px)")
    semi_axes_m: tuple[float, float] = Field(
        (4.0, 4.0), description="landing ellipse semi-axes along world x and y (m)"
    )
    pitch_m: Metres = Field(8.0, gt=0, description="spacing of the candidate ellipse centres")
    max_hazard_fraction: float = Field(
        0.0, ge=0, lt=1, description="a site is safe with at most this share of hazard pixels"
    )

    @field_validator("window_px")
    @classmethod
    def _odd(cls, v: int) -> int:
        if v % 2 == 0:
            raise ValueError(f"must be odd (a centred window), got {v}")
        return v
