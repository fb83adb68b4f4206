"""Options shared by the reconstructions that read slopes from the guide image.

:class:`~simlunar.reconstruction.shading.ShadingOptions` and
:class:`~simlunar.reconstruction.photoclinometry.PhotoclinometryOptions` read the image the
same way (calibration blur and masks, slope gain and clip, the explained-variance band that
caps gamma); each such option is declared once here, so its default, doc and bounds cannot
drift between them.
"""

from __future__ import annotations

from simlunar.registry import Options

__all__ = ["READING_OPTIONS", "ReadingChecks", "check_share_band"]

READING_OPTIONS: dict[str, dict] = {
    "gain": dict(default=1.0, doc="g: divides the calibrated |b| when reading slopes", gt=0, le=10),
    "clip": dict(default=4.0, doc="largest |slope| (dz/dx) read from the image", gt=0, le=100),
    "image_sigma": dict(
        default=1.0, doc="Gaussian sigma smoothing the image before slopes are read (0: none)",
        unit="cell", ge=0, le=32,
    ),
    "share_lo": dict(
        default=0.1, doc="explained-variance share at and below which the result is linear",
        ge=0, lt=1,
    ),
    "share_hi": dict(
        default=0.5, doc="explained-variance share from which gamma = gamma_max", gt=0, le=1
    ),
    "use_flat": dict(
        default=True, doc="divide by the co-located frame when the guide has one",
        choices=(True, False),
    ),
    "sigma_pitch": dict(
        default=0.5, doc="calibration blur sigma as a fraction of the sample pitch", gt=0, le=4
    ),
    "shadow": dict(
        default=0.02, doc="shadowed: at or below this fraction of the 99th percentile",
        ge=0, lt=1,
    ),
    "saturation": dict(default=1.0, doc="saturated: image level at or above this", gt=0),
    "detail_clip": dict(
        default=3.0, doc="the image's re-anchored detail is limited to +- this many times the "
        "RMS of the held-out samples' departure from the kept samples' interpolation (the "
        "linear error's scale at the density; needs heldout_check; 0: no limit)",
        ge=0, le=100,
    ),
    "shadow_lit": dict(
        default=0.02, doc="shadowed too: at or below this fraction of the local lit level, read "
        "from the sun frame, or from sun / co-located frame where that frame is lit "
        "(shadow.shadow_mask; 0: off)",
        ge=0, lt=1,
    ),
}  # fmt: skip
"""name -> keywords of :func:`simlunar.registry.option` (``default`` its first argument), for
:func:`simlunar.registry.shared_option`."""


def check_share_band(options) -> None:
    """``ValueError`` unless ``options.share_lo < options.share_hi`` (gamma's ramp)."""
    if options.share_hi <= options.share_lo:
        raise ValueError(
            f"share_hi must be > share_lo, got {options.share_hi!r} <= {options.share_lo!r}"
        )


class ReadingChecks(Options):
    """Base of an options dataclass that reads slopes from the image: its ``__post_init__``
    checks every field's declared bounds, then the share band (:func:`check_share_band`)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check_share_band(self)
