"""Capture of pattern stacks through Mitsuba: pattern renders, per-frame camera model, guide
view, camera-view truth of the projector correspondences."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy import ndimage

from simlunar.geometry import Rig
from simlunar.imaging.blur import gaussian_blur
from simlunar.imaging.exposure import AUTO_EXPOSURE_LEVEL, AUTO_EXPOSURE_PERCENTILE
from simlunar.imaging.projector_optics import ProjectorOptics, defocus_diameter_px, emit
from simlunar.imaging.sensor import apply_sensor
from simlunar.progress import advance
from simlunar.registry import Options, option
from simlunar.render.lights import ProjectorLight, SunLight
from simlunar.render.scene import TerrainScene, luminance
from simlunar.render.sparse import LitTracer
from simlunar.scanner.triangulate import check_rig, projector_visibility, true_projector_uv

__all__ = [
    "EXPOSURE_PERCENTILE",
    "SPARSE_INTEGRATORS",
    "SPARSE_PARTICLES",
    "Capture",
    "CaptureOptions",
    "GuideView",
    "RenderCapture",
    "camera_truth",
    "render_guide",
]

#: white-frame radiance percentile mapped to ``target_level`` by the auto exposure (the one
#: rule of :mod:`simlunar.imaging.exposure`)
EXPOSURE_PERCENTILE = AUTO_EXPOSURE_PERCENTILE


class Capture(Protocol):
    """What the structured-light scans (:mod:`simlunar.scanner.gray_code`, :mod:`simlunar.scanner.dot_scan`, ...) drive: a camera that
    sees the scene under projector patterns. :class:`RenderCapture` renders through Mitsuba;
    tests use NumPy captures."""

    def render(self, patterns: np.ndarray) -> np.ndarray:
        """Noise-free camera images (n, rows, cols) under ``n`` projector patterns (n, H, W)
        in [0, 1]; each pattern counts as one render."""
        ...

    def sense(self, images: np.ndarray) -> np.ndarray:
        """Captured frames (n, rows, cols): sensor noise, quantisation and response."""
        ...


#: integrators a sparse pattern (a dot frame) may be rendered with
SPARSE_INTEGRATORS = ("path", "ptracer", "lit")
#: light paths per lit projector pixel of the ``"lit"`` sparse integrator
SPARSE_PARTICLES = 256


@dataclass(frozen=True)
class CaptureOptions(Options):
    """Rendering and optics of a :class:`RenderCapture`.

    The camera blur is the finite resolving power of the lens (diffraction and aberrations),
    independent of depth, unlike the thin-lens defocus of ``rig.camera``. The auto exposure
    (:mod:`simlunar.imaging.exposure`) maps the white frame's 99.5th-percentile radiance to
    ``target_level``, so thresholds are in [0, 1] frame units. Sparse patterns (lit fraction
    <= ``sparse_below``) are rendered by the path tracer, by Mitsuba's light tracer from the
    projector (``"ptracer"``, ``sparse_spp`` paths per camera pixel) or by
    :class:`simlunar.render.sparse.LitTracer` (``"lit"``, ``sparse_particles`` paths per lit
    projector pixel, so a dot frame costs what its dots cost). With every integrator a pattern
    with nothing lit (the black frame) is not rendered: it is exactly black.
    """

    max_depth: int = option(3, doc="path depth (2 = direct only; >= 3 includes interreflections)")
    spp: int = option(16, doc="samples per pixel for every pattern")
    seed: int = option(0, doc="sampler seed for every pattern")
    projector_scale: float = option(1.0, doc="projector irradiance scale (Mitsuba scale)")
    projector_gamma: float = option(
        1.0, doc="projector response: pattern values p are emitted as p ** projector_gamma", gt=0
    )
    projector_blur: float = option(
        0.0,
        doc="Gaussian blur sigma of every emitted pattern (projector defocus)",
        unit="px",
        ge=0,
    )
    camera_blur: float = option(
        0.0,
        doc="Gaussian point-spread sigma of the camera lens, applied to every rendered "
        "frame before the sensor",
        unit="px",
        ge=0,
    )
    target_level: float = option(
        AUTO_EXPOSURE_LEVEL,
        doc="fraction of the sensor range (or of 1 without a sensor) the auto exposure maps "
        "the white frame's 99.5th-percentile radiance to, in (0, 1]",
    )
    sparse_integrator: str = option(
        "path", doc="integrator of sparse patterns", choices=SPARSE_INTEGRATORS
    )
    sparse_spp: int | None = option(
        None, doc="samples per pixel of sparse patterns (None: spp); not used by lit", ge=1
    )
    sparse_below: float = option(
        0.01, doc="largest lit fraction of projector pixels counted as sparse, in (0, 1]"
    )
    sparse_particles: int = option(
        SPARSE_PARTICLES,
        doc="lit only: light paths per lit projector pixel (at pattern value 1)",
        ge=1,
    )
    #: the projector's optics (response, pixel aperture, lens PSF and defocus) forming every
    #: pattern's emitted image at sub-pixel resolution
    #: (:mod:`simlunar.imaging.projector_optics`); None: each pattern is emitted as its pixel
    #: grid through ``projector_gamma`` and ``projector_blur``, as before the optics existed
    optics: ProjectorOptics | None = None

    def __post_init__(self):
        super().__post_init__()
        if self.optics is not None:
            if self.projector_gamma != 1.0 or self.projector_blur != 0.0:
                raise ValueError(
                    "projector optics replace projector_gamma and projector_blur: leave "
                    "those at 1 and 0 (the optics have gamma and psf_sigma)"
                )
            if self.sparse_integrator == "lit":
                raise ValueError("the lit sparse integrator traces projector pixels: no optics")


class RenderCapture:
    """Mitsuba-backed :class:`Capture`: projector patterns seen by the rig's triangulation camera.

    Parameters
    ----------
    terrain : Terrain
    rig : Rig
    options : CaptureOptions, optional
        Path depth, samples, projector response and blur, lens blur, exposure level, the
        integrator of sparse patterns.
    bsdf : BSDF spec or None (Lambert)
    sensor : SensorModel or None
        Per-frame noise, quantisation and response; None returns noise-free frames. Its
        exposure is set from the white calibration frame (the auto exposure).
    rng : seed or Generator
        Noise stream (separate from the renderer's seed).
    extra_lights : sequence of light specs
        Sun or ambient light that stays on during the scan (a daylight scan). Light transport
        is linear in the emitters, so their image is rendered once (:attr:`ambient`, at
        ``spp``) and added to every pattern's render: the same frame in expectation as
        rendering them with each pattern, at no cost per frame, and the dot frames keep
        their light tracing from the projector. It appears in the black frame, which the
        decoders subtract; the sensor noise of every frame is drawn on the sum, so the sun's
        shot noise is in every frame.
    """

    def __init__(
        self,
        terrain,
        rig: Rig,
        options: CaptureOptions | None = None,
        *,
        bsdf=None,
        sensor=None,
        rng=None,
        extra_lights=(),
    ) -> None:
        check_rig(rig)
        o = options or CaptureOptions()
        self.options = o
        self.camera_blur = float(o.camera_blur)
        self.sparse_integrator = o.sparse_integrator
        self.sparse_spp = None if o.sparse_spp is None else int(o.sparse_spp)
        self.sparse_below = float(o.sparse_below)
        self.sparse_particles = int(o.sparse_particles)
        self._lit = None  # the LitTracer, made on the first sparse frame
        self.rig = rig
        self.proj_shape = rig.projector.intrinsics.shape
        self.gamma = float(o.projector_gamma)
        self.blur = float(o.projector_blur)
        self.optics = o.optics
        #: (H, W) thin-lens defocus diameter (projector px) at each projector pixel, or None
        self.defocus_px = _defocus_map(terrain, rig, o.optics)
        #: (rows, cols) float32 luminance of ``extra_lights`` alone (None without them),
        #: added to every rendered frame
        self.ambient = _ambient_image(terrain, rig, extra_lights, bsdf, o)
        white = self._white()
        supersample = 1 if o.optics is None else o.optics.supersample
        light = ProjectorLight(
            rig.projector, white[0], scale=o.projector_scale, supersample=supersample
        )
        self.scene = TerrainScene(
            terrain,
            rig.camera,
            lights=[light],
            bsdf=bsdf,
            max_depth=o.max_depth,
            spp=o.spp,
            seed=o.seed,
        )
        self.rng = np.random.default_rng(rng)
        self.renders = 0
        # calibration frame (not counted as a scan render): sets the exposure, on what the
        # camera sees under the white pattern (with the extra lights: a daylight scan is
        # exposed for projector plus sun)
        lit = self.scene.render_patterns(white)
        if not float(np.percentile(lit, EXPOSURE_PERCENTILE)) > 0:
            raise ValueError(
                "the camera does not see the projected area: the white frame is "
                "black in the triangulation camera"
            )
        #: the extra lights' mean image over the pixels the projector lights, relative to
        #: the white pattern's there (0 without extra lights): the sun-to-projector ratio
        #: the camera sees
        self.ambient_ratio = 0.0
        if self.ambient is not None:
            on = lit[0] > 0
            self.ambient_ratio = float(self.ambient[on].mean() / lit[0][on].mean())
        white = self._lens(self._with_ambient(lit))[0]
        ref = float(np.percentile(white, EXPOSURE_PERCENTILE))
        self.gain = o.target_level / ref
        self.sensor = None
        if sensor is not None:
            # electrons per unit radiance so that radiance * gain = 1 is the top of the ADC range
            self.sensor = dataclasses.replace(
                sensor, exposure=self.gain * sensor.max_dn * sensor.gain_e_per_dn
            )

    def _white(self) -> np.ndarray:
        """(1, ...) the white pattern as emitted (the digital all-ones pattern without
        optics, so the scene's texture is exactly that of before the optics existed)."""
        white = np.ones((1, *self.proj_shape), np.float32)
        return white if self.optics is None else self.emitted(white)

    def emitted(self, patterns: np.ndarray) -> np.ndarray:
        """What the projector emits for digital patterns in [0, 1]: through its optics
        (``options.optics``: sub-pixel images) or its response then blur, per pixel."""
        if self.optics is not None:
            return emit(patterns, self.optics, defocus_px=self.defocus_px)
        p = np.clip(np.asarray(patterns, np.float32), 0.0, 1.0) ** self.gamma
        if self.blur > 0:
            p = np.stack([ndimage.gaussian_filter(x, self.blur, mode="nearest") for x in p])
        return p

    def render(self, patterns) -> np.ndarray:
        """Noise-free luminance (n, rows, cols) float32 under ``patterns`` (n, H, W)."""
        pats = np.asarray(patterns, np.float32)
        if pats.ndim != 3 or pats.shape[1:] != tuple(self.proj_shape):
            raise ValueError(
                f"patterns must have shape (n, {self.proj_shape[0]}, "
                f"{self.proj_shape[1]}) for this projector, got {pats.shape}"
            )
        self.renders += len(pats)
        em = self.emitted(pats)
        # a pattern with nothing lit is black: the projector is the scene's only emitter (the
        # extra lights are the separate ambient image), so its render is exactly zero and is
        # skipped (the black frame of every gray-code and dot scan)
        on = (em > 0).any(axis=(1, 2))
        out = np.zeros((len(em), *self.scene.shape), np.float32)
        if on.any():
            out[on] = self._render_emitted(em[on])
        return self._lens(self._with_ambient(out))

    def _render_emitted(self, em: np.ndarray) -> np.ndarray:
        """Luminance under emitted patterns with some light, by the integrator of each."""
        if self.sparse_integrator == "lit":
            return self._render_lit(em)
        sparse = (em > 0).mean(axis=(1, 2)) <= self.sparse_below
        if (self.sparse_integrator == "path" and self.sparse_spp is None) or not sparse.any():
            return self.scene.render_patterns(em)
        out = np.empty((len(em), *self.scene.shape), np.float32)
        if (~sparse).any():
            out[~sparse] = self.scene.render_patterns(em[~sparse])
        out[sparse] = self.scene.render_patterns(
            em[sparse], spp=self.sparse_spp, integrator=self.sparse_integrator
        )
        return out

    def _render_lit(self, em: np.ndarray) -> np.ndarray:
        """``sparse_integrator="lit"``: sparse patterns light traced from their lit pixels
        (:class:`simlunar.render.sparse.LitTracer`), the others path traced."""
        sparse = (em > 0).mean(axis=(1, 2)) <= self.sparse_below
        out = np.empty((len(em), *self.scene.shape), np.float32)
        if (~sparse).any():
            out[~sparse] = self.scene.render_patterns(em[~sparse])
        if sparse.any():
            if self._lit is None:
                self._lit = LitTracer(self.scene, per_pixel=self.sparse_particles)
            out[sparse] = self._lit.render(em[sparse], seed=self.scene.seed)
        return out

    def _with_ambient(self, frames: np.ndarray) -> np.ndarray:
        """``frames`` plus the image of the extra lights (linearity of light transport)."""
        if self.ambient is None:
            return frames
        frames = np.asarray(frames, np.float32)
        if not frames.flags.writeable:
            frames = frames.copy()
        frames += self.ambient
        return frames

    def _lens(self, frames) -> np.ndarray:
        """Camera lens point-spread function (Gaussian, ``camera_blur`` px) on (n, rows, cols).

        Each frame on its own, float32 (:func:`simlunar.imaging.blur.gaussian_blur`, the same
        filter as ``ndimage.gaussian_filter(mode="nearest")``), in place.
        """
        frames = np.asarray(frames, np.float32)
        if self.camera_blur <= 0:
            return frames
        if not frames.flags.writeable:
            frames = frames.copy()
        for i, f in enumerate(frames):
            frames[i] = gaussian_blur(f, self.camera_blur)
        return frames

    def sense(self, images) -> np.ndarray:
        """Captured frames (n, rows, cols) float32 in [0, 1]-ish units: exposure, sensor noise.

        One noise draw per frame, in order, from the capture's noise stream.
        """
        imgs = np.asarray(images)
        if self.sensor is None:
            out = (imgs * np.float32(self.gain)).astype(np.float32, copy=False)
        else:
            out = np.empty(imgs.shape, np.float32)
            for i, im in enumerate(imgs):
                out[i] = apply_sensor(im, self.sensor, rng=self.rng)
        # every captured frame passes here once: the scan's frames stage counts them
        advance(len(out), unit="frames")
        return out


def _ambient_image(terrain, rig: Rig, extra_lights, bsdf, o: CaptureOptions):
    """(rows, cols) float32 luminance of ``extra_lights`` alone in the camera, or None."""
    if not extra_lights:
        return None
    sky = TerrainScene(
        terrain,
        rig.camera,
        lights=list(extra_lights),
        bsdf=bsdf,
        max_depth=o.max_depth,
        spp=o.spp,
        seed=o.seed,
    )
    # one scene in memory at a time (a DLP-size terrain mesh is large): sky goes on return
    return luminance(sky.render()).astype(np.float32)


def _defocus_map(terrain, rig: Rig, optics: ProjectorOptics | None) -> np.ndarray | None:
    """(H, W) defocus disc diameter (projector px) at the depth each projector pixel lights
    (the guide view's ground truth: it is the projector's view); focused at
    ``optics.focus_distance`` or the median of those depths. None without optics or
    without an aperture (``f_number`` 0)."""
    if optics is None or optics.f_number <= 0:
        return None
    white = np.ones(rig.projector.intrinsics.shape, np.float32)
    scene = TerrainScene(terrain, rig.guide, lights=[ProjectorLight(rig.projector, white)], spp=1)
    depth = np.asarray(scene.ground_truth().depth, np.float64)
    del scene
    focus = optics.focus_distance
    if focus is None:
        focus = float(np.nanmedian(depth))
    fx = rig.projector.intrinsics.fx
    return defocus_diameter_px(depth, fx=fx, options=optics, focus=focus)


@dataclass(frozen=True, eq=False)
class GuideView:
    """The co-located guide camera's image and ground truth.

    Attributes
    ----------
    image : (H, W) float64 luminance (planner input)
    depth : (H, W) float64 ground-truth z-depth (NaN off the terrain)
    valid : (H, W) bool
    """

    image: np.ndarray
    depth: np.ndarray
    valid: np.ndarray


def render_guide(
    terrain,
    rig: Rig,
    *,
    light: str = "projector",
    sun=None,
    bsdf=None,
    max_depth: int = 3,
    spp: int = 16,
    seed: int = 0,
) -> GuideView:
    """Render the guide image (projector all-white frame or sun) and its ground-truth depth.

    Parameters
    ----------
    light : "projector" or "sun"
        ``projector``: lit by the co-located projector's all-white frame, a camera-centred
        light, so no cast shadows are visible; ``sun``: lit by ``sun`` (a ``SunLight`` spec).
    """

    H, W = rig.projector.intrinsics.shape
    if light == "projector":
        lights = [ProjectorLight(rig.projector, np.ones((H, W), np.float32))]
    elif light == "sun":
        if not isinstance(sun, SunLight):
            raise ValueError("light='sun' needs sun=SunLight(...)")
        lights = [sun]
    else:
        raise ValueError(f"unknown guide light {light!r}; valid: 'projector', 'sun'")
    scene = TerrainScene(
        terrain, rig.guide, lights=lights, bsdf=bsdf, max_depth=max_depth, spp=spp, seed=seed
    )
    img = luminance(scene.render()).astype(np.float64)
    gt = scene.ground_truth()
    return GuideView(image=img, depth=np.asarray(gt.depth, float), valid=np.asarray(gt.valid))


def camera_truth(capture: RenderCapture, guide: GuideView) -> dict:
    """Ground truth in the triangulation camera: true projector coordinates and projector light.

    Returns a dict with ``uv`` ((rows, cols, 2) float64: the continuous projector coordinates
    where each camera pixel centre's ray meets the projector image, pixel centres at
    ``col + 0.5``; NaN where not lit), ``col``, ``row`` (the pixel it falls in, (rows, cols)
    int, -1 where not lit) and ``lit`` (the surface point each camera pixel sees is lit
    directly by the projector).
    """
    gt = capture.scene.ground_truth()
    lit = projector_visibility(gt.position, capture.rig.projector, guide.depth)
    uv = true_projector_uv(gt.position, capture.rig.projector, lit=lit)
    ok = np.isfinite(uv[..., 0])
    col = np.where(ok, np.floor(np.where(ok, uv[..., 0], 0)), -1).astype(np.int64)
    row = np.where(ok, np.floor(np.where(ok, uv[..., 1], 0)), -1).astype(np.int64)
    return {"uv": uv, "col": col, "row": row, "lit": lit, "valid": np.asarray(gt.valid)}
