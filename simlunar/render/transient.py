"""Time-of-flight capture on mitransient: flash frames and batched steered beams.

Both render the terrain lit by a point laser at the receiver (isotropic, ``laser_intensity``
W/sr), with mitransient's ``transient_path`` integrator and ``transient_hdr_film``: per pixel
(flash) or per beam (steered) a histogram of the returned radiance over round-trip optical
path length (:class:`simlunar.lidar.TimeBins`), the scene's impulse response. The pulse,
jitter, photon noise and the sun are applied afterwards (:mod:`simlunar.lidar`). The sun is
rendered as an ordinary steady image with the same receiver and never as a transient
emitter (mitransient puts a directional emitter's light at a bogus finite path length).

mitransient's transient output is (rows, cols, bins, channels) (not width-first as its
docstring says); memory is rows x cols x bins x 4 channels x 4 bytes, so steered beams are
rendered in batches of a fixed size (one kernel, reused) sorted by their predicted range (the
range gate of :mod:`simlunar.lidar.gate`: from the instrument's pose and a reference plane,
never the terrain), each batch with its own time window (the film's ``start_opl``, an opaque
JIT value).

The film is simlunar's ``simlunar_transient_film``: mitransient's ``transient_hdr_film`` whose
paths are splatted linearly into the two nearest bins (:func:`simlunar.lidar.waveform.splat_paths`
is its NumPy twin) instead of rounded into one, rendered on ``oversample`` times finer bins than
the output: the sub-bin arrival time survives (:mod:`simlunar.lidar.waveform`).

A point laser lights the whole scene, not only a beam's footprint, so interreflections
(``max_depth`` >= 3) are overestimated for steered beams; the default (2) is direct only,
which is exact for a co-located beam and receiver of the same angular profile.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Camera
from simlunar.lidar.returns import TransientOptions
from simlunar.lidar.waveform import TimeBins
from simlunar.render import backend
from simlunar.render import beams as _beams
from simlunar.render.cameras import sensor_dict
from simlunar.render.lights import PROJECTOR_ID, check_pattern, emitter_dicts
from simlunar.render.mesh import terrain_mesh
from simlunar.render.scene import LUMINANCE, TerrainScene, _bsdf_dict, luminance

__all__ = [
    "FlashFrame",
    "PatternFrames",
    "TransientOptions",
    "flash_frame",
    "transient_film",
]

_RGB = LUMINANCE.astype(np.float64)


@dataclass(frozen=True, eq=False)
class FlashFrame:
    """One flash-lidar frame.

    Attributes
    ----------
    steady : (rows, cols) float32
        Laser-lit luminance (the histograms summed over all path lengths).
    histograms : (rows, cols, bins.count * oversample) float32
        Returned luminance per fine time bin (impulse response, tent-splatted).
    sun : (rows, cols) float32 or None
        Steady luminance of the sun alone seen by the receiver pixels.
    bins : TimeBins
        The output bins.
    oversample : int
        Fine bins per output bin.
    sun_irradiance : float
        Irradiance of the rendered sun on a surface facing it (W/m^2; 1 without sun).
    """

    steady: np.ndarray
    histograms: np.ndarray
    sun: np.ndarray | None
    bins: TimeBins
    oversample: int = 1
    sun_irradiance: float = 1.0

    @property
    def binned(self) -> np.ndarray:
        """The histograms summed to the output bins (..., bins.count) float32 (no pulse)."""
        h = self.histograms
        return h.reshape(*h.shape[:-1], -1, int(self.oversample)).sum(axis=-1)


FILM_NAME = "simlunar_transient_film"
_FILM_REGISTERED: list[bool] = []


def _register_film(mi) -> None:
    """Register ``simlunar_transient_film``: mitransient's film with linear (tent) time bins."""
    if _FILM_REGISTERED:
        return
    from mitransient.films.transient_hdr_film import TransientHDRFilm

    class TentTransientFilm(TransientHDRFilm):
        """``transient_hdr_film`` that splats a path into the two bins around its OPL with
        linear weights (the film's first moment is the path's exact OPL), where the parent
        rounds it into one box bin."""

        def add_transient_data(
            self, pos, distance, wavelengths, spec, ray_weight, active, laser_x=0, laser_y=0
        ):
            import drjit as dr

            x = (distance - self.start_opl) / self.bin_width_opl - 0.5
            i0 = dr.floor(x)
            f = x - i0
            for idx, w in ((i0, 1.0 - f), (i0 + 1.0, f)):
                inside = (idx >= 0) & (idx < self.temporal_bins)
                self.transient_storage.put(
                    pos=mi.Vector3f(pos.x, pos.y, idx + 0.5),
                    wavelengths=wavelengths,
                    value=spec * mi.Spectrum(ray_weight * w),
                    alpha=mi.Float(0.0),
                    weight=mi.Float(0.0),
                    active=active & inside,
                    laser_x=laser_x,
                    laser_y=laser_y,
                )

    mi.register_film(FILM_NAME, lambda props: TentTransientFilm(props))
    _FILM_REGISTERED.append(True)


def _mitsuba():
    """Mitsuba with mitransient's plugins, simlunar's film and the beam array registered."""

    mi = backend.mitsuba()
    import mitransient  # noqa: F401  (registers transient_path, transient_hdr_film)

    _register_film(mi)
    _beams.register(mi)
    return mi


def transient_film(width: int, height: int, bins: TimeBins, oversample: int = 1) -> dict:
    """``simlunar_transient_film`` dictionary on ``oversample`` times finer bins than ``bins``
    (box pixel filter: a sample lands in its own pixel; linear splat in time)."""
    fine = bins.refined(oversample)
    return {
        "type": FILM_NAME,
        "width": int(width),
        "height": int(height),
        "temporal_bins": int(fine.count),
        "start_opl": float(fine.start_opl),
        "bin_width_opl": float(fine.bin_opl),
        "rfilter": {"type": "box"},
    }


def _terrain_entries(mi, terrain, bsdf) -> dict:

    return {"terrain": terrain_mesh(terrain, bsdf=mi.load_dict(_bsdf_dict(bsdf, terrain.albedo)))}


def _laser(position, options: TransientOptions) -> dict:
    return {
        "laser": {
            "type": "point",
            "position": [float(x) for x in position],
            "intensity": {"type": "uniform", "value": float(options.laser_intensity)},
        }
    }


def flash_frame(
    terrain,
    camera: Camera,
    *,
    bins: TimeBins,
    options: TransientOptions = TransientOptions(),  # noqa: B008 (frozen)
    bsdf=None,
    sun=None,
    projector=None,
) -> FlashFrame:
    """Render a flash-lidar frame: a receiver array lit by one pulse from its centre.

    Parameters
    ----------
    terrain : Terrain
    camera : geometry.Camera
        The receiver array (perspective pinhole; e.g. 128 x 128), co-located with the laser.
    bins : TimeBins
        Time window (round-trip OPL).
    options : TransientOptions
    bsdf : BSDF spec or None (Lambert)
    sun : SunLight or None
        Rendered separately as a steady image (:attr:`FlashFrame.sun`).
    projector : ProjectorLight or None
        The laser as a pattern projector (a micromirror array lighting chosen directions,
        ``scale`` its irradiance) instead of the isotropic point laser; frames that differ by
        the pattern only: :class:`PatternFrames`.

    Returns
    -------
    FlashFrame
    """
    return PatternFrames(
        terrain, camera, bins=bins, options=options, bsdf=bsdf, sun=sun, projector=projector
    ).render()


class PatternFrames:
    """Flash frames of one receiver, laser and terrain, loaded once: frame after frame differs
    by the projector's pattern only (:meth:`render` with a new ``pattern`` swaps the texture
    through ``mi.traverse``, as :class:`~simlunar.render.scene.TerrainScene` does), and the sun
    image, which no pattern changes, is rendered once.

    The parameters are :func:`flash_frame`'s; a frame rendered here is the frame
    :func:`flash_frame` renders with the same pattern (same seed, same sampler).
    """

    def __init__(
        self,
        terrain,
        camera: Camera,
        *,
        bins: TimeBins,
        options: TransientOptions = TransientOptions(),  # noqa: B008 (frozen)
        bsdf=None,
        sun=None,
        projector=None,
    ) -> None:
        if not isinstance(camera, Camera) or camera.aperture_radius > 0:
            raise ValueError("camera: a flash receiver must be a pinhole geometry.Camera")
        mi = _mitsuba()
        h, w = camera.shape
        sensor = sensor_dict(camera, spp=options.spp)
        sensor["film"] = transient_film(w, h, bins, options.oversample)
        scene = {
            "type": "scene",
            "sensor": sensor,
            "integrator": {"type": "transient_path", "max_depth": int(options.max_depth)},
            **_terrain_entries(mi, terrain, bsdf),
        }
        if projector is None:
            scene.update(_laser(camera.pose.position, options))
        else:
            scene.update(emitter_dicts(projector, camera))
        self._mi, self._scene = mi, mi.load_dict(scene)
        self._params = mi.traverse(self._scene) if projector is not None else None
        self.projector, self.bins, self.options = projector, bins, options
        self._terrain, self._camera, self._bsdf, self._sun = terrain, camera, bsdf, sun
        self._sun_img: np.ndarray | None = None

    def render(self, pattern: np.ndarray | None = None) -> FlashFrame:
        """The frame with the projector showing ``pattern`` (its ``pattern_shape``; None: the
        one shown now)."""
        mi, o = self._mi, self.options
        if pattern is not None:
            if self.projector is None:
                raise ValueError("pattern: these frames have no projector")
            p = check_pattern(pattern, self.projector.pattern_shape)
            self._params[f"{PROJECTOR_ID}.irradiance.data"] = mi.TensorXf(
                np.ascontiguousarray(p[..., None])
            )
            self._params.update()
        steady, hist = mi.render(self._scene, spp=o.spp, seed=o.seed)
        hist = np.asarray(hist, np.float32)  # (rows, cols, bins, channels)
        hist = (hist[..., :3] @ LUMINANCE).astype(np.float32)
        steady_l = luminance(np.asarray(steady, np.float32)[..., :3])
        sun = self._sun
        if sun is not None and self._sun_img is None:
            ts = TerrainScene(self._terrain, self._camera, lights=[sun], bsdf=self._bsdf,
                              max_depth=o.max_depth, spp=o.spp, seed=o.seed)  # fmt: skip
            self._sun_img = luminance(ts.render())
        return FlashFrame(
            steady=steady_l,
            histograms=hist,
            sun=self._sun_img,
            bins=self.bins,
            oversample=o.oversample,
            sun_irradiance=1.0 if sun is None else float(sun.irradiance),
        )
