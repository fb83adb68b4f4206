"""The reconstruction contract: samples (+ optionally what the camera saw) -> a full grid.

Every reconstruction of :data:`simlunar.reconstruction.RECONSTRUCTIONS` has one signature::

    fn(points_rc, values, shape, *, guide: Guide | None, options) -> Reconstructed

``points_rc`` (k, 2) are (row, col) index coordinates of the measured cells, ``values`` (k,)
their measured heights or depths, ``shape`` the output grid. The guide is what the camera saw
in the same view (pixel (r, c) sees cell (r, c)); a reconstruction never sees the truth.
``options`` is the reconstruction's own frozen options dataclass (registered beside it).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simlunar.reconstruction.delaunay import reconstruct
from simlunar.reconstruction.flatfield import FlashGeometry
from simlunar.registry import Options, Registry, option

__all__ = [
    "RECONSTRUCTIONS",
    "Guide",
    "LinearOptions",
    "Reconstructed",
    "linear",
    "run_reconstruction",
]

#: reconstruction name -> Entry(function, options class); ``meta["guided"]``: reads the guide
#: (the entries are registered by :mod:`simlunar.reconstruction`, which imports each module)
RECONSTRUCTIONS = Registry("reconstruction")


def _grid(a, name: str, shape=None) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.ndim == 3:  # (rows, cols, channels) -> mean over channels
        a = a.mean(axis=2)
    if a.ndim != 2:
        raise ValueError(f"guide {name} must have shape (rows, cols), got {a.shape}")
    if shape is not None and a.shape != tuple(shape):
        raise ValueError(f"guide {name} has shape {a.shape}, the image {tuple(shape)}")
    if not np.isfinite(a).all():
        raise ValueError(f"guide {name} contains NaN or infinite values")
    a.setflags(write=False)
    return a


def _direction(d, name: str):
    if d is None:
        return None
    v = np.asarray(d, dtype=np.float64).reshape(-1)
    if v.shape != (3,) or not np.isfinite(v).all() or np.linalg.norm(v) == 0:
        raise ValueError(f"{name} must be a non-zero 3-vector (d_row, d_col, up), got {d!r}")
    v = v / np.linalg.norm(v)
    v.setflags(write=False)
    return v


@dataclass(frozen=True, eq=False)
class Guide:
    """What the camera saw, on the reconstruction's grid.

    Attributes
    ----------
    image : ndarray, shape (rows, cols)
        The guide frame (linear intensity, e.g. the sensor image in [0, 1]) under ``light``.
    light : ndarray, shape (3,), or None
        Unit vector towards the light in grid coordinates ``(d_row, d_col, up)`` (rows grow
        downwards, columns to the right, up out of the surface); None when unknown (a
        reconstruction then calibrates it from the samples and the image).
    flat : ndarray, shape (rows, cols), or None
        A frame of the same view under camera-centred (co-located) light: at opposition the
        image is nearly pure albedo, so ``image / flat`` cancels albedo and keeps shading.
    flash : FlashGeometry or None
        Where the light of ``flat`` is when it is a flash on the rig (a point emitter with
        falloff and a beam): the reconstructions flat-field ``flat`` with it
        (:func:`.flatfield.flat_field` on the samples' linear surface). None: ``flat`` is used
        as it is (the ideal co-located light at infinity, or a flash left uncorrected).
    flat_frames : tuple of str
        The exposures ``flat`` cost, as a reconstruction that reads it records them
        (``("camera",)``; a daylight flash: ``("flash_on", "flash_off")``).
    others : tuple of (image, light)
        Frames of the same view under other suns (photometric stereo), ``light`` as above.
    spacing : float
        Cell size in the units of the sample values per cell (m), so slopes are dz / (spacing).
    frames : tuple of str
        Names of the frames this guide holds (recorded per result row: their exposures cost).
    """

    image: np.ndarray
    light: np.ndarray | None = None
    flat: np.ndarray | None = None
    others: tuple = ()
    spacing: float = 1.0
    frames: tuple = ("sun",)
    flash: FlashGeometry | None = None
    flat_frames: tuple = ("camera",)

    def __post_init__(self):
        img = _grid(self.image, "image")
        object.__setattr__(self, "image", img)
        object.__setattr__(self, "light", _direction(self.light, "light"))
        if self.flat is not None:
            object.__setattr__(self, "flat", _grid(self.flat, "flat", img.shape))
        others = tuple(
            (_grid(im, f"others[{i}] image", img.shape), _direction(d, f"others[{i}] light"))
            for i, (im, d) in enumerate(self.others)
        )
        object.__setattr__(self, "others", others)
        s = float(self.spacing)
        if not np.isfinite(s) or s <= 0:
            raise ValueError(f"guide spacing must be a finite number > 0, got {self.spacing!r}")
        object.__setattr__(self, "spacing", s)
        object.__setattr__(self, "frames", tuple(str(f) for f in self.frames))
        object.__setattr__(self, "flat_frames", tuple(str(f) for f in self.flat_frames))
        if self.flash is not None:
            if not isinstance(self.flash, FlashGeometry):
                raise ValueError(
                    f"guide flash must be a FlashGeometry, got {type(self.flash).__name__}"
                )
            if self.flat is None:
                raise ValueError("guide flash: describes the flat frame's light, but no flat")

    @property
    def shape(self) -> tuple[int, int]:
        return self.image.shape


@dataclass(frozen=True, eq=False)
class Reconstructed:
    """A reconstruction: the grid and what the method reports about itself.

    Attributes
    ----------
    heights : ndarray of float64, shape (rows, cols)
    info : dict of str -> float or str
        Per-method diagnostics recorded with each result row (e.g. ``shading_share``: the
        share of the image explained by shading on the samples; ``frames``: the guide frames
        used).
    """

    heights: np.ndarray
    info: dict = field(default_factory=dict)


@dataclass(frozen=True)
class LinearOptions(Options):
    """Options of the Delaunay-linear reconstruction (the paper's, section 4.1)."""

    outside: str = option(
        "nearest",
        doc="cells outside the samples' convex hull: the nearest sample's value, or NaN",
        choices=("nearest", "nan"),
    )
    hull_edge_ratio: float = option(
        0.0,
        doc="border treatment: hull triangles whose longest edge exceeds this many times the "
        "median edge are peeled off and their cells filled as outside (slivers of samples a "
        "fraction of a pixel off the border; simlunar.reconstruction.delaunay.trim_hull); 0 = "
        "the whole Delaunay hull",
        ge=0,
    )


def linear(points_rc, values, shape, *, guide=None, options: LinearOptions | None = None):
    """Delaunay-linear interpolation of the samples (:func:`.delaunay.reconstruct`); the
    guide is not used."""
    o = options or LinearOptions()
    return Reconstructed(
        reconstruct(points_rc, values, shape, outside=o.outside, hull_edge_ratio=o.hull_edge_ratio)
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
