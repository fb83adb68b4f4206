"""Reconstructions of a full grid from scattered samples, optionally guided by the image.

``RECONSTRUCTIONS`` names each reconstruction with its options class (one entry per
reconstruction, :mod:`simlunar.registry`); every one has the signature of
:mod:`simlunar.reconstruction.base` and is run by name with :func:`run_reconstruction`.
``reconstruct`` is the Delaunay-linear interpolation of the paper (section 4.1).
"""

from simlunar.reconstruction.base import (
    RECONSTRUCTIONS,
    Guide,
    LinearOptions,
    Reconstructed,
    linear,
    run_reconstruction,
)
from simlunar.reconstruction.control import SmoothedOptions, smoothed
from simlunar.reconstruction.delaunay import OUTSIDE_POLICIES, reconstruct, triangulate
from simlunar.reconstruction.learned import LearnedReconOptions, learned_reconstruction
from simlunar.reconstruction.photoclinometry import PhotoclinometryOptions, photoclinometry
from simlunar.reconstruction.shading import ShadingOptions, shading

# the registry lives in .base (the learned reconstruction reads it); its entries are added here
RECONSTRUCTIONS.register(
    "linear", linear, LinearOptions, summary="Delaunay-linear (the paper's)", guided=False
)
RECONSTRUCTIONS.register(
    "shading",
    shading,
    ShadingOptions,
    summary="slope along the sun, anchored",
    guided=True,
    # 2: the held-out check pools its folds at sparse densities and remakes the detail from
    # the kept samples only (it was checked as made from all of them); 3: a flash's second
    # pass (flash_refine) reads around the fused surface's slopes with the relief gain; 4: the
    # detail is limited to detail_clip x the held-out departures' RMS, and a calibration whose
    # held-out share cannot be formed is not used
    results_version=4,
)
RECONSTRUCTIONS.register(
    "photoclinometry",
    photoclinometry,
    PhotoclinometryOptions,
    summary="linearised photoclinometry, sparse least squares",
    guided=True,
    # 2: the held-out check (option heldout_check, on by default) caps gamma; 3: the detail is
    # limited to detail_clip x the held-out departures' RMS, and a calibration whose held-out
    # share cannot be formed is not used
    results_version=3,
)
RECONSTRUCTIONS.register(
    "smoothed", smoothed, SmoothedOptions, summary="image-free control", guided=False
)
RECONSTRUCTIONS.register(
    "learned",
    learned_reconstruction,
    LearnedReconOptions,
    summary="linear + a trained image residual",
    guided=True,
    needs_model=True,
    # 2: the held-out check (option heldout_check, on by default) weighs the residual
    results_version=2,
)


__all__ = [
    "OUTSIDE_POLICIES",
    "RECONSTRUCTIONS",
    "Guide",
    "LearnedReconOptions",
    "LinearOptions",
    "PhotoclinometryOptions",
    "Reconstructed",
    "ShadingOptions",
    "SmoothedOptions",
    "learned_reconstruction",
    "linear",
    "photoclinometry",
    "reconstruct",
    "run_reconstruction",
    "shading",
    "smoothed",
    "triangulate",
]
