"""The auto-exposure rule, one for every simulated capture.

A reference radiance image (the rendered guide image of a sampling study; the white
calibration frame of a structured-light scan) is scaled so that its
``AUTO_EXPOSURE_PERCENTILE``-th percentile lands at ``AUTO_EXPOSURE_LEVEL`` of the sensor's
range: with a sensor that is ``exposure = gain * full_well_e`` electrons per unit radiance
(:class:`simlunar.imaging.sensor.SensorModel`), without one the image is multiplied by ``gain``
(and clipped to [0, 1] where a [0, 1] image is needed). The 0.5 % brightest pixels may
saturate; the rest keep 20 % headroom.
"""

from __future__ import annotations

import numpy as np

__all__ = ["AUTO_EXPOSURE_LEVEL", "AUTO_EXPOSURE_PERCENTILE", "auto_exposure_e", "auto_gain"]

#: percentile of the reference radiance that the auto exposure places at ...
AUTO_EXPOSURE_PERCENTILE = 99.5
#: ... this fraction of the sensor range (of the full well; of 1 without a sensor)
AUTO_EXPOSURE_LEVEL = 0.8


def auto_gain(
    reference: np.ndarray,
    *,
    level: float = AUTO_EXPOSURE_LEVEL,
    percentile: float = AUTO_EXPOSURE_PERCENTILE,
) -> float:
    """Scale factor that maps the ``percentile`` of ``reference`` to ``level``.

    Parameters
    ----------
    reference : ndarray
        Linear radiance; NaN counts as 0.
    level : float
        Target value (fraction of the sensor range), > 0.
    percentile : float
        Percentile in [0, 100].

    Returns
    -------
    float
        ``level / percentile(reference)``; 1.0 when that percentile is not positive (a black
        reference: nothing to expose for).
    """
    ref = np.nan_to_num(np.asarray(reference), nan=0.0)  # its own dtype: same rounding
    top = float(np.percentile(ref, percentile))
    return float(level) / top if top > 0 else 1.0


def auto_exposure_e(reference: np.ndarray, full_well_e: float) -> float:
    """Electrons per unit radiance under the rule: ``auto_gain(reference) * full_well_e``.

    Computed as ``level * full_well_e / percentile`` (one rounding order, so results do not
    move by an ulp between callers); a black reference gives ``full_well_e``.
    """
    ref = np.nan_to_num(np.asarray(reference), nan=0.0)  # its own dtype: same rounding
    top = float(np.percentile(ref, AUTO_EXPOSURE_PERCENTILE))
    return AUTO_EXPOSURE_LEVEL * float(full_well_e) / top if top > 0 else float(full_well_e)
