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
from simlunar.lidar.footprint import FootprintOptions
from simlunar.lidar.waveform import TimeBins
from simlunar.render import backend
from simlunar.render import beams as _beams
from simlunar.render.cameras import film_dict, sensor_dict
from simlunar.render.lights import emitter_dicts
from simlunar.render.mesh import terrain_mesh
from simlunar.render.scene import LUMINANCE, TerrainScene, _bsdf_dict, luminance

__all__ = [
    "BeamCapture",
    "BeamReturns",
    "FlashFrame",
    "TransientOptions",
    "capture_beams",
    "flash_frame",
    "transient_film",
]

_RGB = LUMINANCE.astype(np.float64)


@dataclass(frozen=True)
class TransientOptions:
    """Rendering of time-of-flight returns.

    Parameters
    ----------
    spp : int
        Samples per pixel of a flash frame (steered beams use ``FootprintOptions.samples``).
    max_depth : int
        Longest path (2 = direct only; see the module note on steered beams).
    seed : int
        Sampler seed.
    laser_intensity : float
        Radiant intensity of the point laser (W/sr); the histograms scale with it.
    oversample : int
        Rendered (fine) time bins per output bin. With the linear splat of the film, 2 keeps
        a plane's noise-free range within 0.01 mm at 0.65 pulse sigma per bin and 0.2 mm at
        0.44 (tests/lidar/test_ranging.py); memory grows with it.
    """

    spp: int = 64
    max_depth: int = 2
    seed: int = 0
    laser_intensity: float = 1.0
    oversample: int = 2

    def __post_init__(self) -> None:
        if int(self.spp) < 1 or int(self.seed) < 0:
            raise ValueError("spp must be >= 1 and seed >= 0")
        if int(self.oversample) < 1:
            raise ValueError(f"oversample must be >= 1, got {self.oversample}")
        if self.max_depth == 0 or self.max_depth < -1:
            raise ValueError(f"max_depth must be -1 or >= 1, got {self.max_depth}")
        if not self.laser_intensity > 0:
            raise ValueError(f"laser_intensity must be > 0 W/sr, got {self.laser_intensity}")


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
    options: TransientOptions = TransientOptions(),
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
        ``scale`` its irradiance) instead of the isotropic point laser.

    Returns
    -------
    FlashFrame
    """

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
    steady, hist = mi.render(mi.load_dict(scene), spp=options.spp, seed=options.seed)
    hist = np.asarray(hist, np.float32)  # (rows, cols, bins, channels)
    hist = (hist[..., :3] @ LUMINANCE).astype(np.float32)
    steady_l = luminance(np.asarray(steady, np.float32)[..., :3])
    sun_img = None
    if sun is not None:
        ts = TerrainScene(
            terrain,
            camera,
            lights=[sun],
            bsdf=bsdf,
            max_depth=options.max_depth,
            spp=options.spp,
            seed=options.seed,
        )
        sun_img = luminance(ts.render())
    return FlashFrame(
        steady=steady_l,
        histograms=hist,
        sun=sun_img,
        bins=bins,
        oversample=options.oversample,
        sun_irradiance=1.0 if sun is None else float(sun.irradiance),
    )


@dataclass(frozen=True, eq=False)
class BeamReturns:
    """Rendered returns of steered beams (arrays over the beams, in the input order).

    Attributes
    ----------
    histograms : (n, bins * oversample) float32
        Returned luminance per fine time bin (tent-splatted); output bin j of beam i starts
        at round-trip OPL ``start_opl[i] + j * bin_opl``.
    start_opl : (n,) float64
        Start of each beam's window (m of round-trip OPL; NaN where the centre ray missed).
    bin_opl : float
        Output bin width (m of round-trip OPL).
    steady : (n,) float32
        Laser-lit luminance over all path lengths.
    sun : (n,) float32 or None
        Steady luminance of the sun alone in each beam's profile.
    predicted_range : (n,) float64
        The gate's expected range of each beam (m; from the instrument's pose and reference
        plane, :mod:`simlunar.lidar.gate`), NaN = not fired.
    opl_offset : (n,) float64 or None
        A moving platform's render shortcut: the extra round-trip path ``d . delta`` (m) of a
        beam whose laser sat ``delta`` from its origin (:func:`capture_beams`); subtract half
        of it from the range.
    """

    histograms: np.ndarray
    start_opl: np.ndarray
    bin_opl: float
    steady: np.ndarray
    sun: np.ndarray | None
    predicted_range: np.ndarray
    oversample: int = 1
    opl_offset: np.ndarray | None = None

    @property
    def binned(self) -> np.ndarray:
        """The histograms summed to the output bins (..., bins.count) float32 (no pulse)."""
        h = self.histograms
        return h.reshape(*h.shape[:-1], -1, int(self.oversample)).sum(axis=-1)


class BeamCapture:
    """Steered beams from one origin over a terrain, rendered ``batch`` beams per launch.

    Parameters
    ----------
    terrain : Terrain
    origin : (3,) float
        Beam origin = laser = receiver (world, m).
    footprint : FootprintOptions
        Angular profile; ``samples`` rays per beam.
    window : TimeBins
        Bin width and count of every beam's window (its ``start_opl`` is set per batch).
    options : TransientOptions
    bsdf : BSDF spec or None (Lambert)
    sun : SunLight or None
        If given, :meth:`render` also returns each beam's steady sun luminance.
    batch : int
        Beams per launch (the film is batch x 1 x bins x 4 float32).
    """

    def __init__(
        self,
        terrain,
        origin,
        *,
        footprint: FootprintOptions,
        window: TimeBins,
        options: TransientOptions = TransientOptions(),
        bsdf=None,
        sun=None,
        batch: int = 4096,
    ) -> None:

        mi = self._mi = _mitsuba()
        self.batch, self.window = int(batch), window
        self.oversample = int(options.oversample)
        self.origin = np.asarray(origin, float).reshape(3)
        scene = {
            "type": "scene",
            "sensor": _beams.sensor_dict(
                self.batch, transient_film(self.batch, 1, window, self.oversample), footprint
            ),
            "integrator": {"type": "transient_path", "max_depth": int(options.max_depth)},
            **_terrain_entries(mi, terrain, bsdf),
            **_laser(self.origin, options),
        }
        self._scene = mi.load_dict(scene)
        self._sensor = self._scene.sensors()[0]
        self._seed = int(options.seed)
        self._params = None
        self._sun_scene = None
        self.sun_irradiance = 1.0 if sun is None else float(sun.irradiance)
        if sun is not None:
            sun_scene = {
                "type": "scene",
                "sensor": _beams.sensor_dict(self.batch, film_dict(self.batch, 1), footprint),
                "integrator": {"type": "path", "max_depth": int(options.max_depth)},
                **_terrain_entries(mi, terrain, bsdf),
                **emitter_dicts(sun, None),
            }
            self._sun_scene = mi.load_dict(sun_scene)

    @property
    def has_sun(self) -> bool:
        """Whether :meth:`render_sun` is available."""
        return self._sun_scene is not None

    def cast(self, directions: np.ndarray) -> np.ndarray:
        """Range (m) of the first hit of each beam's centre ray (n,); NaN = miss.

        The terrain's truth: for tests and benchmarks only, never used by a scan (its range
        gate comes from :mod:`simlunar.lidar.gate`)."""
        import drjit as dr

        mi = self._mi
        d, _, _ = _beams.tangent_frames(np.asarray(directions, float))
        d32 = np.ascontiguousarray(d.T, np.float32)
        o = np.broadcast_to(self.origin.astype(np.float32)[:, None], d32.shape)
        ray = mi.Ray3f(
            mi.Point3f(o[0].copy(), o[1].copy(), o[2].copy()), mi.Vector3f(d32[0], d32[1], d32[2])
        )
        si = self._scene.ray_intersect(ray)
        valid, t = si.is_valid(), si.t
        dr.eval(valid, t)
        valid = np.broadcast_to(np.asarray(valid, bool).reshape(-1), len(d))
        return np.where(valid, np.asarray(t, float).reshape(-1), np.nan)

    def _launch(self, scene, directions: np.ndarray, seed: int, origins=None):
        n = len(directions)
        pad = np.concatenate([directions, np.repeat(directions[-1:], self.batch - n, axis=0)])
        o = self.origin if origins is None else np.asarray(origins, float).reshape(n, 3)
        if origins is not None:
            o = np.concatenate([o, np.repeat(o[-1:], self.batch - n, axis=0)])
        sensor = scene.sensors()[0]
        _beams.set_beams(self._mi, sensor, o, pad)
        return self._mi.render(scene, seed=seed)

    def set_laser(self, position) -> None:
        """Move the laser (a moving platform; no kernel recompilation)."""
        if self._params is None:
            self._params = self._mi.traverse(self._scene)
        p = np.asarray(position, float).reshape(3)
        self._params["laser.position"] = self._mi.Point3f(*(float(x) for x in p))
        self._params.update()

    def render_batch(self, directions: np.ndarray, start_opl: float, seed: int = 0, origins=None):
        """Histograms (n, bins * oversample) and steady luminance (n,) of n <= batch beams
        (window start m); ``origins`` (n, 3): each beam's own origin (else the capture's),
        the laser where :meth:`set_laser` put it."""
        import drjit as dr

        film = self._sensor.film()
        film.start_opl = dr.opaque(self._mi.Float, float(start_opl))  # no recompilation
        steady, hist = self._launch(self._scene, directions, seed, origins)
        n = len(directions)
        hist = np.asarray(hist, np.float32)[0, :n, :, :3] @ LUMINANCE
        return hist.astype(np.float32), luminance(np.asarray(steady, np.float32)[0, :n, :3])

    def render_sun(self, directions: np.ndarray, seed: int = 0, origins=None) -> np.ndarray:
        """Steady sun luminance (n,) of n <= batch beams."""
        if self._sun_scene is None:
            raise ValueError("this BeamCapture was built without a sun")
        img = self._launch(self._sun_scene, directions, seed, origins)
        return luminance(np.asarray(img, np.float32)[0, : len(directions), :3])


def capture_beams(
    capture: BeamCapture,
    directions: np.ndarray,
    predicted_range: np.ndarray,
    *,
    margin_m: float = 1.0,
    seed: int = 0,
    origins: np.ndarray | None = None,
    max_shift_m: float = 0.1,
) -> BeamReturns:
    """Render the returns of many beams, batched and range-gated around predicted ranges.

    The predicted ranges come from what the instrument knows (its pose and a reference plane,
    :mod:`simlunar.lidar.gate`), never from the terrain. Beams are sorted by them and cut into
    batches of at most ``capture.batch`` whose predictions fit the window with ``margin_m`` on
    each side; each batch's window starts ``margin_m`` before its nearest prediction. A return
    outside its window is lost, as with a real range gate.

    Parameters
    ----------
    capture : BeamCapture
    directions : (n, 3) float
        Unit world directions of the beams.
    predicted_range : (n,) float
        Expected range of each beam (m); NaN = not fired.
    margin_m : float
        Range margin (m) on both sides of the predicted ranges.
    seed : int
        Sampler seed of the first batch (batch k uses seed + k).
    origins : (n, 3) float or None
        Each beam's origin (a moving platform, in firing order: beams whose origins are
        within ``max_shift_m`` of the first of their group share a launch); None: the
        capture's origin.
    max_shift_m : float
        Largest distance (m) between a beam's origin and its launch's laser, which sits at
        the group's mean origin: the render is then bistatic by ``delta`` and its round-trip
        path is ``2 R + d . delta`` to ``|delta|^2 / (2 R)``; :attr:`BeamReturns.opl_offset`
        holds ``d . delta`` for the reader to remove.

    Returns
    -------
    BeamReturns
    """
    d = np.asarray(directions, float)
    n, nb = len(d), capture.window.count
    nf = nb * capture.oversample
    pred = np.asarray(predicted_range, float).reshape(-1)
    if pred.shape != (n,):
        raise ValueError(f"predicted_range must have shape ({n},), got {pred.shape}")
    hist = np.zeros((n, nf), np.float32)
    start = np.full(n, np.nan)
    steady = np.zeros(n, np.float32)
    sun = np.zeros(n, np.float32) if capture.has_sun else None
    span = capture.window.bin_range * nb - 2.0 * margin_m
    if span <= 0:
        raise ValueError(f"window of {capture.window.bin_range * nb} m is shorter than 2 margins")
    offset = np.zeros(n)
    fired = np.flatnonzero(np.isfinite(pred))
    groups = [fired]
    if origins is not None:
        o = np.asarray(origins, float).reshape(n, 3)
        groups, first = [], 0
        for q in range(1, len(fired) + 1):  # consecutive beams (firing order) near the first
            if q == len(fired) or np.linalg.norm(o[fired[q]] - o[fired[first]]) > max_shift_m:
                groups.append(fired[first:q])
                first = q
    k = 0
    for group in groups:
        beam_o = None
        if origins is not None:
            beam_o = o[group]
            laser = beam_o.mean(axis=0)
            capture.set_laser(laser)
            offset[group] = np.sum(d[group] * (beam_o - laser), axis=1)
        order = group[np.argsort(pred[group])]
        i = 0
        while i < len(order):
            r0 = pred[order[i]]
            j = min(i + capture.batch, len(order))
            j = i + int(np.searchsorted(pred[order[i:j]], r0 + span, side="right"))
            idx = order[i:j]
            bo = None if beam_o is None else o[idx]
            s0 = 2.0 * max(r0 - margin_m, 0.0)
            hist[idx], steady[idx] = capture.render_batch(d[idx], s0, seed + k, origins=bo)
            start[idx] = s0
            if sun is not None:
                sun[idx] = capture.render_sun(d[idx], seed + k, origins=bo)
            i, k = j, k + 1
    if origins is not None:
        capture.set_laser(capture.origin)
    return BeamReturns(
        histograms=hist,
        start_opl=start,
        bin_opl=capture.window.bin_opl,
        steady=steady,
        sun=sun,
        predicted_range=pred,
        oversample=capture.oversample,
        opl_offset=offset,
    )
