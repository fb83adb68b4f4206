"""One Mitsuba scene per terrain view, kept and mutated: render, ground truth, pattern stacks.

``TerrainScene`` loads the scene once. Changing the projector pattern writes the new texture
through ``mi.traverse`` (``<projector>.irradiance.data``) and ``params.update()``: no scene
reload and, because the texture is a JIT variable of fixed size, no kernel recompilation
(``benchmarks/bench_render.py::pattern_swap`` counts compiles).

Path depth (``max_depth``, Mitsuba's convention): 1 shows only emitters seen directly, 2 is
direct illumination only (one bounce from the light to the surface to the camera), 3 adds one
interreflection, -1 is unbounded. Crater interreflections need >= 3.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Camera, OrthoCamera
from simlunar.geometry.types import GroundTruth
from simlunar.render import backend
from simlunar.render.bsdfs import bsdf_dict
from simlunar.render.cameras import sensor_dict
from simlunar.render.lights import (
    PROJECTOR_ID,
    AmbientLight,
    CameraLight,
    FlashLight,
    ProjectorLight,
    SunLight,
    check_pattern,
    emitter_dicts,
)
from simlunar.render.materials import LambertBSDF
from simlunar.render.mesh import albedo_texture, terrain_mesh

__all__ = [
    "FINITE_TRIES",
    "LUMINANCE",
    "RenderResult",
    "TerrainScene",
    "finite_pixels",
    "inverse_by_linearity",
    "luminance",
    "render",
]

#: Rec. 709 / sRGB luminance weights of linear RGB
LUMINANCE = np.array([0.2126, 0.7152, 0.0722], np.float32)


#: renders tried in all by :func:`finite_pixels` before it gives up
FINITE_TRIES = 4


def finite_pixels(launch, seed: int) -> np.ndarray:
    """``launch(seed)``'s image with every non-finite value re-estimated by another launch.

    A pixel value is a Monte Carlo estimate; a sample that fails in float32 makes it inf or
    NaN (Mitsuba's light tracer on ``cuda_ad_rgb`` put one inf pixel into 2 of 6 frames of
    a 96 x 128 dot pattern at 16 spp; ``llvm_ad_rgb`` never did). Such values (per pixel
    and channel) are taken from a render with another seed, ``seed + i * 0x9E3779B1`` mod
    2^32 for i = 1, 2, ...: an independent estimate of the same expectation, so the image
    stays unbiased and reproducible; the finite values are left as they are. Raises
    ``RuntimeError`` when :data:`FINITE_TRIES` renders still leave one.
    """
    img = launch(seed)
    for i in range(1, FINITE_TRIES):
        bad = ~np.isfinite(img)
        if not bad.any():
            return img
        img[bad] = launch((seed + i * 0x9E3779B1) % 2**32)[bad]
    n = int((~np.isfinite(img)).sum())
    if n:
        raise RuntimeError(
            f"the renderer gave {n} non-finite pixels in {FINITE_TRIES} renders with "
            f"different seeds (seed {seed}): the scene itself is degenerate"
        )
    return img


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Linear RGB (..., 3) to luminance (...) as float32."""
    return (np.asarray(rgb, np.float32) @ LUMINANCE).astype(np.float32)


def inverse_by_linearity(
    white: np.ndarray, images: np.ndarray, black: np.ndarray | None = None
) -> np.ndarray:
    """Images under the inverse patterns ``1 - p`` without rendering them.

    Light transport is linear in the projector's irradiance, so
    ``I(1 - p) = I(1) - I(p) + I(0)``; ``I(0)`` (``black``: the scene with the projector off)
    is zero when the projector is the only light. Valid for noise-free (rendered) images:
    add sensor noise per frame afterwards (:mod:`simlunar.imaging.sensor`).

    Parameters
    ----------
    white : (rows, cols) float
        Image with an all-ones pattern.
    images : (n, rows, cols) float
        Images under the patterns.
    black : (rows, cols) float or None
        Image with the all-zeros pattern (other lights only).
    """
    out = np.asarray(white, np.float32)[None] - np.asarray(images, np.float32)
    if black is not None:
        out = out + np.asarray(black, np.float32)[None]
    return out.astype(np.float32)


def _check_int(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {value}")
    return int(value)


def _bsdf_dict(bsdf, albedo: np.ndarray) -> dict:

    sigma_map = getattr(bsdf, "sigma_map", None)
    if sigma_map is not None and sigma_map.shape != np.shape(albedo):
        raise ValueError(
            f"bsdf.sigma_map has shape {sigma_map.shape}; it must match the terrain grid "
            f"{np.shape(albedo)} (one roughness per cell)"
        )
    return bsdf_dict(LambertBSDF() if bsdf is None else bsdf, albedo_texture(albedo))


def _bounds(terrain) -> tuple[np.ndarray, np.ndarray]:
    xmin, xmax, ymin, ymax = terrain.extent
    h = terrain.heights
    return (np.array([xmin, ymin, np.nanmin(h)]), np.array([xmax, ymax, np.nanmax(h)]))


class TerrainScene:
    """A terrain seen by one camera under a list of lights, as one mutable Mitsuba scene.

    Parameters
    ----------
    terrain : Terrain
        Heights, albedo (the BSDF's reflectance texture), spacing, origin.
    camera : geometry.Camera or geometry.OrthoCamera
        Perspective (optionally thin-lens) or orthographic view.
    lights : sequence of light specs
        :class:`SunLight`, :class:`CameraLight`, :class:`FlashLight`, :class:`ProjectorLight` (at most one),
        :class:`AmbientLight`. At least one.
    bsdf : BSDF spec or None
        ``materials.LambertBSDF`` / ``OrenNayarBSDF`` / ``HapkeBSDF``; None means Lambert.
        An ``OrenNayarBSDF`` with a ``sigma_map`` (terrain shape) gets per-cell roughness.
    max_depth : int
        Longest path (Mitsuba convention: 2 = direct light only, 3 = one interreflection,
        -1 = unbounded).
    spp : int
        Default samples per pixel (> 0).
    seed : int
        Default sampler seed (>= 0); the same seed gives the same image.
    """

    def __init__(
        self,
        terrain,
        camera,
        *,
        lights,
        bsdf=None,
        max_depth: int = 3,
        spp: int = 16,
        seed: int = 0,
    ) -> None:

        mi = backend.mitsuba()
        if not isinstance(camera, (Camera, OrthoCamera)):
            raise ValueError(
                f"camera: unknown camera type {type(camera).__name__}; valid: Camera "
                "(perspective / thin lens), OrthoCamera (orthographic)"
            )
        if np.isnan(terrain.heights).all():
            raise ValueError("terrain.heights: every cell is nodata (NaN); nothing to render")
        self.spp = _check_int("spp", spp, 1)
        self.seed = _check_int("seed", seed, 0)
        max_depth = _check_int("max_depth", max_depth, -1)
        if max_depth == 0:
            raise ValueError("max_depth must be -1 (unbounded) or >= 1, got 0")
        self.max_depth = max_depth
        lights = list(lights) if lights is not None else []
        if not lights:
            raise ValueError("lights: at least one light is needed")
        valid = (SunLight, CameraLight, FlashLight, ProjectorLight, AmbientLight)
        for i, light in enumerate(lights):
            if not isinstance(light, valid):
                raise ValueError(
                    f"lights[{i}]: unknown light spec {type(light).__name__}; "
                    f"valid: {', '.join(c.__name__ for c in valid)}"
                )
        projectors = [li for li in lights if isinstance(li, ProjectorLight)]
        if len(projectors) > 1:
            raise ValueError("lights: at most one ProjectorLight per scene")
        self.terrain, self.camera, self.lights, self.bsdf = terrain, camera, lights, bsdf
        self.projector = projectors[0] if projectors else None

        bounds = _bounds(terrain)
        bsdf_obj = mi.load_dict(_bsdf_dict(bsdf, terrain.albedo))
        scene = {
            "type": "scene",
            "terrain": terrain_mesh(terrain, bsdf=bsdf_obj),
            "sensor": sensor_dict(camera, spp=self.spp, bounds=bounds),
            "integrator": {"type": "path", "max_depth": max_depth},
        }
        for i, light in enumerate(lights):
            # the one projector keeps the plain id that set_pattern addresses
            idx = 0 if isinstance(light, ProjectorLight) else i
            scene.update(emitter_dicts(light, camera, index=idx))
        self._mi = mi
        self._scene = mi.load_dict(scene)
        self._params = mi.traverse(self._scene)
        self._pattern_key = f"{PROJECTOR_ID}.irradiance.data"
        self._pattern = self.projector.pattern if self.projector is not None else None
        self._ptracer = None

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(int(s) for s in self.camera.shape)  # type: ignore[return-value]

    @property
    def pattern(self) -> np.ndarray | None:
        """The projector pattern now in the scene (read-only), or None without projector."""
        return self._pattern

    def render(
        self, spp: int | None = None, seed: int | None = None, *, integrator: str = "path"
    ) -> np.ndarray:
        """Linear radiance image, float32 (rows, cols, 3) (W m^-2 sr^-1 per unit irradiance).

        ``integrator``: ``"path"`` (the scene's path tracer) or ``"ptracer"`` (Mitsuba's light
        tracer with the same ``max_depth``: paths start at the emitters, which sample their
        lit area, and are splatted onto the film; ``spp`` then counts light paths per film
        pixel). Both estimate the same image; light tracing pays for sparse emission
        (projector dots).
        """
        spp = self.spp if spp is None else _check_int("spp", spp, 1)
        seed = self.seed if seed is None else _check_int("seed", seed, 0)
        if integrator == "path":
            kwargs = {}
        elif integrator == "ptracer":
            if self._ptracer is None:
                self._ptracer = self._mi.load_dict({"type": "ptracer", "max_depth": self.max_depth})
            kwargs = {"integrator": self._ptracer}
        else:
            raise ValueError(f"unknown integrator {integrator!r}; valid: 'path', 'ptracer'")

        def launch(s: int) -> np.ndarray:
            img = self._mi.render(self._scene, spp=spp, seed=s, **kwargs)
            return np.array(img, dtype=np.float32, copy=True)[..., :3]

        return finite_pixels(launch, seed)

    def set_pattern(self, pattern) -> None:
        """Show ``pattern`` (projector shape (h, w), values >= 0) without reloading the scene."""
        if self.projector is None:
            raise ValueError("pattern: this scene has no ProjectorLight")
        p = check_pattern(pattern, self.projector.pattern_shape)
        self._params[self._pattern_key] = self._mi.TensorXf(np.ascontiguousarray(p[..., None]))
        self._params.update()
        self._pattern = p

    def render_patterns(
        self,
        patterns,
        *,
        spp: int | None = None,
        seed: int | None = None,
        inverses: bool = False,
        integrator: str = "path",
    ):
        """Luminance images under a stack of projector patterns, rendered in this scene.

        Parameters
        ----------
        patterns : (n, h, w) array
            Projector patterns (projector resolution).
        spp, seed : int or None
            Override the scene defaults; every pattern uses the same seed.
        inverses : bool
            Also return the images under ``1 - pattern``, obtained by linearity
            (:func:`inverse_by_linearity`) from two extra renders (all-ones and all-zeros
            pattern) instead of n more. Noise-free: add sensor noise per frame afterwards.
        integrator : "path" or "ptracer"
            See :meth:`render`.

        Returns
        -------
        images : (n, rows, cols) float32
            Linear luminance.
        inverse_images : (n, rows, cols) float32
            Only when ``inverses`` is True (then a tuple ``(images, inverse_images)``).
        """
        if self.projector is None:
            raise ValueError("patterns: this scene has no ProjectorLight")
        pats = np.asarray(patterns, np.float32)
        shape = self.projector.pattern_shape
        if pats.ndim != 3 or pats.shape[1:] != tuple(shape):
            raise ValueError(
                f"patterns must have shape (n, {shape[0]}, {shape[1]}), got {pats.shape}"
            )
        original = self._pattern
        out = np.empty((len(pats), *self.shape), np.float32)
        try:
            for i, p in enumerate(pats):
                self.set_pattern(p)
                out[i] = luminance(self.render(spp, seed, integrator=integrator))
            if not inverses:
                return out
            self.set_pattern(np.ones(shape, np.float32))
            white = luminance(self.render(spp, seed, integrator=integrator))
            self.set_pattern(np.zeros(shape, np.float32))
            black = luminance(self.render(spp, seed, integrator=integrator))
        finally:
            self.set_pattern(original)
        return out, inverse_by_linearity(white, out, black)

    def ground_truth(self) -> GroundTruth:
        """Exact geometry seen through each pixel centre.

        One ray per pixel centre (``u = c + 1/2``, ``v = r + 1/2``) is generated by the scene's
        own sensor (so the same frame conversion as the render; through the lens centre for
        a thin lens) and intersected with the terrain. Mitsuba's ``aov`` integrator is not
        used because it averages over random positions inside each pixel, whereas the
        ground truth is defined at pixel centres (and must equal the DEM there).

        Returns
        -------
        GroundTruth
            ``depth`` = z-depth along the optical axis, ``(p - C) . forward`` with ``C`` the
            camera centre (orthographic: distance from the image plane), float64;
            ``position`` world (m) float64; ``normal`` world unit shading normal float32;
            ``valid``. NaN where invalid.
        """
        rows, cols = self.shape
        v, u = np.mgrid[0:rows, 0:cols].astype(np.float64)
        u, v = (u + 0.5).ravel(), (v + 0.5).ravel()
        valid, pos, nrm = self._cast(u, v)
        # A nadir camera's pixel centres fall exactly on mesh vertices (one vertex per cell
        # centre), where the ray/triangle test may let a ray slip between the triangles, and
        # the terrain's outer cell centres lie exactly on the mesh boundary. Retry each miss
        # with four rays (+-e, +-e) px around the centre and average the hits: symmetric
        # offsets cancel the first-order position error, so the result is exact on planar
        # patches (border pixels only have inward hits: error e * spacing * slope there).
        # e must exceed float32's resolution of u / cols (2^-24 * cols px: 1e-4 px at 1600).
        miss = np.flatnonzero(~valid)
        if miss.size:
            e = max(2e-5, 8 * max(rows, cols) * 2.0**-24)
            acc_p = np.zeros((miss.size, 3))
            acc_n = np.zeros((miss.size, 3))
            count = np.zeros(miss.size)
            for du, dv in ((e, e), (-e, e), (e, -e), (-e, -e)):
                ok, p2, n2 = self._cast(u[miss] + du, v[miss] + dv)
                acc_p[ok] += p2[ok]
                acc_n[ok] += n2[ok]
                count[ok] += 1
            ok = count > 0
            hit = miss[ok]
            valid[hit] = True
            pos[hit] = acc_p[ok] / count[ok, None]
            n_avg = acc_n[ok] / np.linalg.norm(acc_n[ok], axis=1, keepdims=True)
            nrm[hit] = n_avg.astype(np.float32)
        valid = valid.reshape(rows, cols)
        pos = pos.reshape(rows, cols, 3)
        nrm = nrm.reshape(rows, cols, 3)
        pos[~valid] = np.nan
        nrm[~valid] = np.nan
        depth = (pos - self.camera.pose.position) @ self.camera.pose.forward
        return GroundTruth(depth=depth, position=pos, normal=nrm, valid=valid)

    def _cast(self, u: np.ndarray, v: np.ndarray):
        """Intersect the sensor's rays through pixel coordinates (u, v) (n,) with the scene."""
        import drjit as dr

        mi = self._mi
        rows, cols = self.shape
        n = len(u)
        sensor = self._scene.sensors()[0]
        half = np.full(n, 0.5, np.float32)
        ray, _ = sensor.sample_ray(
            mi.Float(np.zeros(n, np.float32)),
            mi.Float(half),
            mi.Point2f((u / cols).astype(np.float32), (v / rows).astype(np.float32)),
            mi.Point2f(half, half),
        )
        si = self._scene.ray_intersect(ray)
        hit, p, nrm = si.is_valid(), si.p, si.sh_frame.n
        dr.eval(hit, p, nrm)  # one kernel for the three outputs (else one trace per output)
        valid = np.array(hit, bool).reshape(-1)
        valid = np.broadcast_to(valid, (n,)).copy()
        pos = np.array(p, np.float64).reshape(3, -1).T
        nrm = np.array(nrm, np.float32).reshape(3, -1).T
        return valid, np.broadcast_to(pos, (n, 3)).copy(), np.broadcast_to(nrm, (n, 3)).copy()


@dataclass(frozen=True, eq=False)
class RenderResult:
    """A rendered image and its ground truth for the same view.

    Attributes
    ----------
    image : (rows, cols, 3) float32
        Linear radiance.
    gt : GroundTruth
    """

    image: np.ndarray
    gt: GroundTruth


def render(
    terrain, camera, *, lights, bsdf=None, spp: int = 16, seed: int = 0, max_depth: int = 3
) -> RenderResult:
    """Render ``terrain`` once and return the image with its ground truth.

    See :class:`TerrainScene` for the parameters. Build a :class:`TerrainScene` instead when
    rendering the same view several times (pattern stacks, several seeds).
    """
    scene = TerrainScene(
        terrain, camera, lights=lights, bsdf=bsdf, max_depth=max_depth, spp=spp, seed=seed
    )
    return RenderResult(image=scene.render(), gt=scene.ground_truth())
