"""Steered beams rendered in batches with mitransient (only simlunar/render imports Mitsuba).

A :class:`BeamCapture` (made for a steered beam's options by :func:`beam_capture`) holds one
transient scene whose sensor fires many beams from one origin (each a footprint of rays,
:mod:`simlunar.render.beams`); :func:`capture_beams` (:meth:`BeamCapture.render_beams`) cuts the
beams into range-gated batches around the ranges the instrument predicts
(:mod:`simlunar.lidar.gate`) and returns their histograms as :class:`BeamReturns`. The film, the
laser and the terrain entries are the flash's (:mod:`simlunar.render.transient`). The steered
scan that reads them (ordering, photon counts, ranging, timing) is :mod:`simlunar.lidar.scan`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.lidar.footprint import FootprintOptions
from simlunar.lidar.returns import TransientOptions
from simlunar.lidar.scan import SteeredBeamOptions
from simlunar.lidar.waveform import TimeBins
from simlunar.progress import stage
from simlunar.render import beams as _beams
from simlunar.render.cameras import film_dict
from simlunar.render.lights import emitter_dicts
from simlunar.render.scene import LUMINANCE, luminance
from simlunar.render.transient import _laser, _mitsuba, _terrain_entries, transient_film

__all__ = [
    "BeamCapture",
    "BeamReturns",
    "beam_capture",
    "capture_beams",
]


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
        options: TransientOptions = TransientOptions(),  # noqa: B008 (frozen, as before the move)
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

    def render_beams(self, directions: np.ndarray, predicted_range: np.ndarray, **kwargs):
        """:func:`capture_beams` of this capture: the returns of many beams, batched and
        range-gated around their predicted ranges (what a scan of
        :mod:`simlunar.lidar.scan` calls)."""
        return capture_beams(self, directions, predicted_range, **kwargs)


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
    pred = np.asarray(predicted_range, float).reshape(-1)
    if pred.shape != (len(d),):
        raise ValueError(f"predicted_range must have shape ({len(d)},), got {pred.shape}")
    out = _empty_returns(capture, pred)
    width = capture.window.bin_range * capture.window.count
    span = width - 2.0 * margin_m
    if span <= 0:
        raise ValueError(f"window of {width} m is shorter than 2 margins")
    fired = np.flatnonzero(np.isfinite(pred))
    o = None if origins is None else np.asarray(origins, float).reshape(len(d), 3)
    groups = [fired] if o is None else _origin_groups(fired, o, max_shift_m)
    k = 0
    with stage("beams", total=len(fired), unit="beams") as beams:
        for group in groups:
            if o is not None:
                out.opl_offset[group] = _place_laser(capture, d[group], o[group])
            order = group[np.argsort(pred[group])]
            for idx, s0 in _gated_batches(order, pred, capture.batch, span, margin_m):
                _render_batch_into(out, capture, idx, d, s0, seed + k, o)
                k += 1
                beams.advance(len(idx))
    if origins is not None:
        capture.set_laser(capture.origin)
    return out


def _empty_returns(capture: BeamCapture, pred: np.ndarray) -> BeamReturns:
    """The :class:`BeamReturns` of beams with predicted ranges ``pred`` (n,) m before any is
    rendered: zero histograms and luminances, NaN window starts, zero laser offsets."""
    n = len(pred)
    return BeamReturns(
        histograms=np.zeros((n, capture.window.count * capture.oversample), np.float32),
        start_opl=np.full(n, np.nan),
        bin_opl=capture.window.bin_opl,
        steady=np.zeros(n, np.float32),
        sun=np.zeros(n, np.float32) if capture.has_sun else None,
        predicted_range=pred,
        oversample=capture.oversample,
        opl_offset=np.zeros(n),
    )


def _render_batch_into(out: BeamReturns, capture: BeamCapture, idx, d, start_opl, seed, origins):
    """Render the beams ``idx`` (directions ``d[idx]``, origins ``origins[idx]`` or the
    capture's) in one launch whose window starts at ``start_opl`` (m) and write their
    histograms, luminances and window start into ``out``."""
    bo = None if origins is None else origins[idx]
    out.histograms[idx], out.steady[idx] = capture.render_batch(d[idx], start_opl, seed, origins=bo)
    out.start_opl[idx] = start_opl
    if out.sun is not None:
        out.sun[idx] = capture.render_sun(d[idx], seed, origins=bo)


def _origin_groups(fired: np.ndarray, origins: np.ndarray, max_shift_m: float) -> list:
    """Runs of consecutive fired beams (firing order) whose origins lie within ``max_shift_m``
    of the run's first: index arrays into the beams, one launch position each."""
    groups, first = [], 0
    for q in range(1, len(fired) + 1):
        if (
            q == len(fired)
            or np.linalg.norm(origins[fired[q]] - origins[fired[first]]) > max_shift_m
        ):
            groups.append(fired[first:q])
            first = q
    return groups


def _place_laser(capture: BeamCapture, d: np.ndarray, origins: np.ndarray) -> np.ndarray:
    """Put the laser at the mean of a launch group's beam origins (n, 3) m; return each beam's
    extra round-trip path ``d . delta`` (m) from its origin's offset ``delta``."""
    laser = origins.mean(axis=0)
    capture.set_laser(laser)
    return np.sum(d * (origins - laser), axis=1)


def _gated_batches(order: np.ndarray, pred: np.ndarray, batch: int, span: float, margin_m: float):
    """Consecutive slices of ``order`` (beams sorted by predicted range) of at most ``batch``
    beams whose predictions lie within ``span`` (m) of the slice's first, each with its
    window's start (round-trip OPL, m): ``margin_m`` before the first prediction."""
    i = 0
    while i < len(order):
        r0 = pred[order[i]]
        j = min(i + batch, len(order))
        j = i + int(np.searchsorted(pred[order[i:j]], r0 + span, side="right"))
        yield order[i:j], 2.0 * max(r0 - margin_m, 0.0)
        i = j


def beam_capture(terrain, origin, *, options: SteeredBeamOptions, sun=None, bsdf=None):
    """The reusable render of a steered beam at ``origin`` (3,) m over ``terrain``: a
    :class:`BeamCapture` with ``options``' footprint, window, rendering and batch size (the
    capture :func:`simlunar.lidar.scan.steered_beam_scan` reads)."""
    return BeamCapture(
        terrain,
        origin,
        footprint=options.footprint,
        window=options.window,
        options=options.transient,
        bsdf=bsdf,
        sun=sun,
        batch=options.batch,
    )
