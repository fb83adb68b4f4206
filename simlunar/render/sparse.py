"""Light tracing from the lit projector pixels: a sparse frame costs what its lit pixels cost.

Mitsuba's ``ptracer`` launches ``spp`` particles per *camera* pixel whatever the projector
shows (``AdjointIntegrator::render``: a wavefront of ``film width x height x spp`` samples), so a
frame of 1 000 dots on a 2048 x 1536 camera traces 3.1 M light paths at ``spp`` 1. Its projector
emitter does sample the lit pixels in proportion to the pattern, so those particles all start
at the dots; only their number is wrong. :class:`LitTracer` chooses the number: ``per_pixel``
particles per lit projector pixel (at pattern value 1), so a frame's cost follows its lit
pixels, and several frames share one launch.

The estimator is the particle tracer's (Veach's light tracing with a pinhole projector):

1. :func:`lit_particles` (NumPy): for each frame, ``N_f = ceil(per_pixel * S_f)`` particles with
   ``S_f`` the sum of the emitted pattern; particle ``j`` picks the lit pixel whose cumulative
   mass holds ``(j + xi_j) / N_f`` (stratified: each pixel gets its share of particles within
   one, with probability proportional to its value), lands at a stratified position across the
   pixel (the same number, rescaled) and at a golden-ratio (Kronecker) position down it with one
   random shift per frame. Each particle's marginal is uniform over the emitted power, so the
   frame is unbiased; stratification only lowers the variance.
2. :class:`LitTracer`: a ray from the projector's pinhole through the particle's projector
   position carries power ``scale * S_f / (f_x f_y N_f)`` (the projector's irradiance at unit
   distance is ``scale * pattern``, a pixel covers ``1 / (f_x f_y)`` there: Mitsuba's projector
   ``sample_ray`` weight). At every surface vertex up to ``max_depth`` the path is connected to
   the camera (``sensor.sample_direction``, visibility by ``scene.ray_test``, the BSDF towards
   the camera with Veach's shading-normal correction) and splatted into the camera pixel that
   contains the connection (the films use a box filter); the path continues by BSDF sampling.
   Splats are scaled by the film's pixel count over ``N_f``, as the ptracer scales by
   ``1 / spp`` with ``film pixels x spp`` particles: the frames are in the units of
   :meth:`simlunar.render.scene.TerrainScene.render` (luminance per unit pattern).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simlunar.render import backend
from simlunar.render.scene import LUMINANCE

__all__ = ["LitParticles", "LitTracer", "lit_particles"]

#: frac(j * GOLDEN) spreads consecutive particles of one pixel down it (Kronecker sequence)
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: largest offset within a projector pixel (float32 resolves 2^-13 px at 1024 px)
X_MAX = 1.0 - 2.0**-11
#: path depth after which Russian roulette ends paths (unbounded ``max_depth`` only)
RR_DEPTH = 5
#: the most vertices an unbounded path may have
MAX_VERTICES = 64


@dataclass(frozen=True, eq=False)
class LitParticles:
    """Particles leaving the projector for a stack of frames: a table of the lit pixels.

    Particle ``k`` leaves lit pixel ``i = pixel[k]``; with ``j = k - first[i]`` (the pixel's
    particles are contiguous) it crosses the pixel at ``(j + offset[i]) / share[i]`` and down it
    at ``frac(j * GOLDEN + shift[i])`` (:meth:`uv`; the tracer does the same on the device).

    Attributes
    ----------
    pixel : (N,) int32
        Lit pixel (row of the table) of each particle.
    frame, col, row : (L,) int32
        Frame and projector pixel of each lit pixel.
    first : (L,) int64
        Its first particle.
    share : (L,) float64
        Its expected particle count ``N_f v / S_f`` (its actual count is within one of it).
    offset, shift : (L,) float64
        Its systematic offset in ``[0, 1)`` and its Kronecker shift.
    power : (n,) float64
        Sum of the emitted pattern over each frame's lit pixels, ``S_f``.
    counts : (n,) int64
        Particles per frame, ``N_f`` (0 for a frame with nothing lit).
    """

    pixel: np.ndarray
    frame: np.ndarray
    col: np.ndarray
    row: np.ndarray
    first: np.ndarray
    share: np.ndarray
    offset: np.ndarray
    shift: np.ndarray
    power: np.ndarray
    counts: np.ndarray

    def __len__(self) -> int:
        return int(self.pixel.shape[0])

    def uv(self) -> np.ndarray:
        """(N, 2) float64 projector pixel coordinates (u, v) of the particles."""
        i = self.pixel
        j = np.arange(len(i)) - self.first[i]
        x = np.clip((j + self.offset[i]) / self.share[i], 0.0, X_MAX)
        y = j * GOLDEN + self.shift[i]
        y = np.minimum(y - np.floor(y), X_MAX)
        return np.stack([self.col[i] + x, self.row[i] + y], axis=-1)


def lit_particles(emitted, *, per_pixel: float, rng=None) -> LitParticles:
    """Systematic particles over the lit pixels of each pattern, in proportion to its value.

    Frame ``f`` gets ``N = ceil(per_pixel * S_f)`` particles; its particle ``k`` takes the lit
    pixel whose share of the frame's power holds ``(k + xi) / N`` (one random ``xi`` per
    frame: systematic sampling, so each pixel gets its share ``N v / S`` within one) and
    crosses it at that number's position within the share (a regular grid); down the pixel
    its ``j``-th particle goes to ``frac(j * GOLDEN + eta)`` (a Kronecker sequence, one random
    ``eta`` per pixel). Each particle on its own is uniform over the emitted power, so the
    estimate is unbiased; the regular placement only lowers its variance.

    Parameters
    ----------
    emitted : (n, H, W) float array
        What the projector emits (values >= 0; response and blur already applied).
    per_pixel : float
        Particles per lit pixel at value 1.
    rng : seed or Generator
        The random shifts.

    Returns
    -------
    LitParticles
    """
    em = np.asarray(emitted, np.float32)
    if em.ndim != 3:
        raise ValueError(f"emitted must be (n, H, W), got shape {em.shape}")
    if not per_pixel > 0:
        raise ValueError(f"per_pixel must be > 0, got {per_pixel}")
    rng = np.random.default_rng(rng)
    f, row, col = np.nonzero(em > 0)
    val = em[f, row, col].astype(np.float64)
    power = np.bincount(f, weights=val, minlength=len(em))
    counts = np.zeros(len(em), np.int64)
    lit = power > 0
    counts[lit] = np.maximum(1, np.ceil(per_pixel * power[lit] - 1e-9)).astype(np.int64)
    share = val * (counts[f] / power[f])
    # B: the share of the frame's earlier lit pixels; particle k of the frame is in pixel i
    # when B_i <= k + xi < B_i + share_i, so the pixel's first is ceil(B_i - xi)
    start = np.concatenate([[0], np.cumsum(counts)])
    csum = np.cumsum(share)
    before = csum - share - np.concatenate([[0.0], csum])[np.searchsorted(f, np.arange(len(em)))][f]
    xi = rng.random(len(em))[f]
    local = np.minimum(np.ceil(before - xi), counts[f])  # rounding: never past the frame's end
    first = start[f] + local.astype(np.int64)
    nxt = np.append(first[1:], start[-1])
    pixel = np.repeat(np.arange(len(f), dtype=np.int32), nxt - first)
    offset = np.clip(local + xi - before, 0.0, 1.0)
    return LitParticles(
        pixel=pixel,
        frame=f.astype(np.int32),
        col=col.astype(np.int32),
        row=row.astype(np.int32),
        first=first,
        share=share,
        offset=offset,
        shift=rng.random(len(f)),
        power=power,
        counts=counts,
    )


class LitTracer:
    """Light tracer of a :class:`~simlunar.render.scene.TerrainScene`'s projector frames.

    Parameters
    ----------
    scene : TerrainScene
        With a :class:`~simlunar.render.lights.ProjectorLight`; its geometry, camera,
        ``max_depth`` and projector (pose, intrinsics, ``scale``) are used, its pattern is not.
    per_pixel : float
        Particles per lit projector pixel at pattern value 1.
    batch : int
        Frames traced in one launch (memory: ``batch`` camera images of float32).
    """

    def __init__(self, scene, *, per_pixel: float = 256.0, batch: int = 8) -> None:
        if scene.projector is None:
            raise ValueError("scene: the lit tracer needs a scene with a ProjectorLight")
        if not per_pixel > 0:
            raise ValueError(f"per_pixel must be > 0, got {per_pixel}")
        if int(batch) < 1:
            raise ValueError(f"batch must be >= 1, got {batch}")
        self._mi = backend.mitsuba()
        self._scene = scene._scene  # the loaded Mitsuba scene (render/ internals)
        self.shape = scene.shape
        self.max_depth = scene.max_depth
        self.per_pixel = float(per_pixel)
        self.batch = int(batch)
        proj = scene.projector
        k = proj.projector.intrinsics
        self.proj_shape = k.shape
        self._k = (float(k.fx), float(k.fy), float(k.cx), float(k.cy))
        self._rotation = np.asarray(proj.projector.pose.rotation, float)
        self._origin = np.asarray(proj.projector.pose.position, float)
        #: power through one projector pixel of value 1 (projector irradiance at unit distance
        #: ``scale`` times the pixel's area there)
        self.pixel_power = float(proj.scale) / (k.fx * k.fy)
        self._sampler = self._mi.load_dict({"type": "independent"})

    def render(self, emitted, *, seed: int = 0) -> np.ndarray:
        """Luminance frames (n, rows, cols) float32 under emitted patterns (n, H, W).

        ``emitted`` is what the projector emits (values >= 0, no response applied here). A
        frame with nothing lit is black and costs nothing.
        """
        em = np.asarray(emitted, np.float32)
        if em.ndim != 3 or em.shape[1:] != tuple(self.proj_shape):
            raise ValueError(
                f"emitted must have shape (n, {self.proj_shape[0]}, {self.proj_shape[1]}), "
                f"got {em.shape}"
            )
        if np.any(em < 0) or not np.all(np.isfinite(em)):
            raise ValueError("emitted patterns must be finite and >= 0")
        out = np.zeros((len(em), *self.shape), np.float32)
        rng = np.random.default_rng(seed)
        for start in range(0, len(em), self.batch):
            sub = em[start : start + self.batch]
            parts = lit_particles(sub, per_pixel=self.per_pixel, rng=rng)
            if len(parts):
                launch_seed = int(rng.integers(0, 2**31))
                out[start : start + len(sub)] = self._trace(parts, len(sub), launch_seed)
        return out

    def _trace(self, parts: LitParticles, n_frames: int, seed: int) -> np.ndarray:
        """One launch: trace ``parts`` and return their (n_frames, rows, cols) splats."""
        import drjit as dr

        mi = self._mi
        rows, cols = self.shape
        sampler = self._sampler.clone()
        sampler.seed(dr.opaque(mi.UInt32, seed), len(parts))
        with np.errstate(divide="ignore", invalid="ignore"):
            per_particle = np.where(parts.counts > 0, parts.power / parts.counts, 0.0)
        power = per_particle * (self.pixel_power * rows * cols)
        i = mi.UInt32(parts.pixel.astype(np.uint32))
        frame = dr.gather(mi.UInt32, _table(mi.UInt32, parts.frame), i)
        throughput = dr.gather(mi.Float, _table(mi.Float, power[parts.frame]), i)
        ray = mi.Ray3f(mi.Point3f(*(float(c) for c in self._origin)), self._directions(parts, i))
        image = dr.zeros(mi.Float, n_frames * rows * cols)
        self._paths(ray, mi.Color3f(throughput), sampler, image, frame * (rows * cols))
        dr.eval(image)
        return np.array(image, np.float32).reshape(n_frames, rows, cols)

    def _directions(self, parts: LitParticles, i):
        """World unit directions of the particles' rays (:meth:`LitParticles.uv` on the device)."""
        import drjit as dr

        mi = self._mi
        j = mi.Float(
            dr.arange(mi.UInt32, len(parts))
            - dr.gather(mi.UInt32, _table(mi.UInt32, parts.first), i)
        )
        x = (j + dr.gather(mi.Float, _table(mi.Float, parts.offset), i)) * dr.gather(
            mi.Float, _table(mi.Float, 1.0 / np.maximum(parts.share, 1e-30)), i
        )
        y = j * GOLDEN + dr.gather(mi.Float, _table(mi.Float, parts.shift), i)
        u = mi.Float(dr.gather(mi.UInt32, _table(mi.UInt32, parts.col), i)) + dr.clip(x, 0.0, X_MAX)
        v = mi.Float(dr.gather(mi.UInt32, _table(mi.UInt32, parts.row), i)) + dr.minimum(
            y - dr.floor(y), X_MAX
        )
        fx, fy, cx, cy = self._k
        x, y = (u - cx) / fx, (v - cy) / fy
        r = self._rotation.tolist()
        d = mi.Vector3f(
            r[0][0] * x + r[0][1] * y + r[0][2],
            r[1][0] * x + r[1][1] * y + r[1][2],
            r[2][0] * x + r[2][1] * y + r[2][2],
        )
        return dr.normalize(d)

    def _paths(self, ray, throughput, sampler, image, base) -> None:
        """Trace from the projector, connecting every vertex before ``max_depth`` to the camera."""
        import drjit as dr

        mi = self._mi
        scene = self._scene
        ctx = mi.BSDFContext(mi.TransportMode.Importance)
        active = mi.Bool(True)
        si = scene.ray_intersect(ray, active)
        active &= si.is_valid()
        depth = 1
        limit = MAX_VERTICES if self.max_depth < 0 else self.max_depth
        while depth < limit:
            bsdf = si.bsdf(ray)
            self._connect(si, bsdf, throughput, sampler, image, base, active)
            if depth + 1 >= limit:
                break
            bs, weight = bsdf.sample(
                ctx, si, sampler.next_1d(active), sampler.next_2d(active), active
            )
            wo = si.to_world(bs.wo)
            wi_geo, wo_geo = dr.dot(si.n, -ray.d), dr.dot(si.n, wo)
            cos_wi, cos_wo = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(bs.wo)
            # no light leaks through shading normals; adjoint BSDF correction (Veach 1997, p. 155)
            active &= (wi_geo * cos_wi > 0) & (wo_geo * cos_wo > 0)
            throughput = throughput * weight * dr.abs(cos_wi * wo_geo / (cos_wo * wi_geo))
            active &= dr.max(throughput) > 0
            ray = si.spawn_ray(wo)
            si = scene.ray_intersect(ray, active)
            active &= si.is_valid()
            depth += 1
            if self.max_depth < 0:
                if depth > RR_DEPTH:
                    q = dr.minimum(dr.max(throughput), 0.95)
                    active &= sampler.next_1d(active) < q
                    throughput = throughput / q
                if not dr.any(active):
                    break

    def _connect(self, si, bsdf, throughput, sampler, image, base, active) -> None:
        """Splat the path's contribution at vertex ``si`` into the camera pixel it is seen in."""
        import drjit as dr

        mi = self._mi
        sensor = self._scene.sensors()[0]
        ds, importance = sensor.sample_direction(si, sampler.next_2d(active), active)
        ok = active & (ds.pdf > 0)
        shadow = si.spawn_ray_to(ds.p)
        ok &= ~self._scene.ray_test(shadow, ok)
        local = si.to_local(shadow.d)
        wi_geo, wo_geo = dr.dot(si.n, si.to_world(si.wi)), dr.dot(si.n, shadow.d)
        cos_wi, cos_wo = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(local)
        ok &= (wi_geo * cos_wi > 0) & (wo_geo * cos_wo > 0)
        ctx = mi.BSDFContext(mi.TransportMode.Importance)
        value = throughput * importance * bsdf.eval(ctx, si, local, ok)
        value *= dr.abs(cos_wi * wo_geo / (cos_wo * wi_geo))
        lum = LUMINANCE.tolist()
        y = lum[0] * value.x + lum[1] * value.y + lum[2] * value.z
        rows, cols = self.shape
        col = mi.Int32(dr.floor(ds.uv.x))
        row = mi.Int32(dr.floor(ds.uv.y))
        ok &= (col >= 0) & (col < cols) & (row >= 0) & (row < rows)
        index = base + mi.UInt32(row * cols + col)
        dr.scatter_reduce(dr.ReduceOp.Add, image, y, index, ok)


def _table(kind, values: np.ndarray):
    """A device array of ``values`` padded to two entries at least: an array of one entry
    would be a literal of the kernel, and every new value a new kernel to compile."""
    dtype = np.uint32 if "UInt" in kind.__name__ else np.float32
    v = np.asarray(values).astype(dtype)
    if v.size < 2:
        v = np.concatenate([v, np.zeros(2 - v.size, dtype)])
    return kind(v)
