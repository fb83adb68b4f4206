"""Reconstructions of a full grid from scattered samples, optionally guided by the image.

``RECONSTRUCTIONS`` names each reconstruction with its options class (one entry per
reconstruction, :mod:`simlunar.registry`); every one has the signature of
:mod:`simlunar.reconstruction.base` and is run by name with :func:`run_reconstruction`.
``reconstruct`` is the Delaunay-linear interpolation of the paper (section 4.1).
"""

from simlunar.reconstruction.base import Guide, LinearOptions, Reconstructed, linear
from simlunar.reconstruction.control import SmoothedOptions, smoothed
from simlunar.reconstruction.delaunay import OUTSIDE_POLICIES, reconstruct, triangulate
from simlunar.reconstruction.learned import LearnedReconOptions, learned_reconstruction
from simlunar.reconstruction.photoclinometry import PhotoclinometryOptions, photoclinometry
from simlunar.reconstruction.shading import ShadingOptions, shading
from simlunar.registry import Registry

#: reconstruction name -> Entry(function, options class); ``meta["guided"]``: reads the guide
RECONSTRUCTIONS = Registry("reconstruction")
RECONSTRUCTIONS.register(
    "linear", linear, LinearOptions, summary="Delaunay-linear (the paper's)", guided=False
)
RECONSTRUCTIONS.register(
    "shading", shading, ShadingOptions, summary="slope along the sun, anchored", guided=True
)
RECONSTRUCTIONS.register(
    "photoclinometry",
    photoclinometry,
    PhotoclinometryOptions,
    summary="linearised photoclinometry, sparse least squares",
    guided=True,
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
)


def run_reconstruction(name, points_rc, values, shape, *, guide=None, options=None):
    """Run reconstruction ``name`` on the samples.

    Parameters
    ----------
    name : str
        A name of :data:`RECONSTRUCTIONS` (an unknown one is a ``ValueError`` listing them).
    points_rc : array_like, shape (k, 2)
        Measured cells (row, col).
    values : array_like, shape (k,)
        Measured heights or depths there.
    shape : tuple of int
        Output grid (rows, cols).
    guide : Guide, optional
        What the camera saw; a guided reconstruction without one is a ``ValueError``.
    options : the entry's options object, a mapping of its fields, or None (defaults)

    Returns
    -------
    Reconstructed
    """
    entry, options = RECONSTRUCTIONS.resolve(name, options)
    if entry.meta.get("guided") and guide is None:
        raise ValueError(f"reconstruction {name!r} needs the guide image (guide=Guide(...))")
    return entry.target(points_rc, values, shape, guide=guide, options=options)


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
