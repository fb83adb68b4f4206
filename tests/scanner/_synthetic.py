"""A NumPy structured-light 'renderer' for planes: exact, fast, independent of Mitsuba.

Each camera pixel is split into ``ss x ss`` sub-rays; each hits the plane ``n . X = d`` and
picks up the projector pattern value at its projector pixel (nearest, as Mitsuba's projector
texture with ``filter_type='nearest'``) times the albedo. No shading, no interreflection.
With ``optics`` (:class:`simlunar.imaging.projector_optics.ProjectorOptics`) each pattern is
first formed by the projector's optics at sub-pixel resolution and the sub-rays sample that
image bilinearly, as the render capture's supersampled texture.
"""

from __future__ import annotations

import numpy as np


class PlaneCapture:
    def __init__(self, rig, normal, offset, *, ss=3, albedo=0.8, noise=0.0, rng=0, optics=None):
        self.rig = rig
        self.optics = optics
        self.normal = np.asarray(normal, float) / np.linalg.norm(normal)
        self.offset = float(offset)
        self.noise = noise
        self.rng = np.random.default_rng(rng)
        self.renders = 0
        rows, cols = rig.camera.intrinsics.shape
        off = (np.arange(ss) + 0.5) / ss
        v, u = np.mgrid[0:rows, 0:cols].astype(float)
        su = (u[..., None, None] + off[None, None, None, :]).repeat(ss, axis=2)
        sv = (v[..., None, None] + off[None, None, :, None]).repeat(ss, axis=3)
        uv = np.stack([su, sv], axis=-1).reshape(rows, cols, ss * ss, 2)
        X = self.intersect(rig.camera, uv)
        puv, z = rig.projector.project(X)
        H, W = rig.projector.intrinsics.shape
        ok = (z > 0) & (puv[..., 0] >= 0) & (puv[..., 0] < W) & (puv[..., 1] >= 0)
        ok &= puv[..., 1] < H
        self.ok = ok
        self.pc = np.where(ok, np.floor(np.where(ok, puv[..., 0], 0)), 0).astype(int)
        self.pr = np.where(ok, np.floor(np.where(ok, puv[..., 1], 0)), 0).astype(int)
        self.puv = np.where(ok[..., None], puv, 0.0)
        self.albedo = albedo

    def intersect(self, cam, uv):
        o, d = cam.rays(uv)
        t = (self.offset - o @ self.normal) / (d @ self.normal)
        return o + t[..., None] * d

    def true_depth(self, cam):
        X = self.intersect(cam, cam.pixel_centers())
        return cam.pose.world_to_device(X)[..., 2]

    def true_uv(self):
        """(rows, cols, 2) continuous projector coordinates of each camera pixel centre's ray."""
        X = self.intersect(self.rig.camera, self.rig.camera.pixel_centers())
        return self.rig.projector.project(X)[0]

    def render(self, patterns):
        patterns = np.asarray(patterns, float)
        self.renders += len(patterns)
        if self.optics is not None:
            return self.albedo * self._render_optics(patterns)
        vals = patterns[:, self.pr, self.pc] * self.ok[None]
        return self.albedo * vals.mean(axis=-1)

    def sense(self, images):
        images = np.asarray(images, float)
        if self.noise > 0:
            images = images + self.rng.normal(0, self.noise, images.shape)
        return images

    def _render_optics(self, patterns):
        from scipy import ndimage

        from simlunar.imaging.projector_optics import emit

        S = self.optics.supersample
        # sub-pixel sample (i, j) has its centre at projector (j + 0.5) / S: bilinear at
        # sample index S u - 0.5, clamped at the border (the texture's clamp)
        x = S * self.puv[..., 0] - 0.5
        y = S * self.puv[..., 1] - 0.5
        out = []
        for em in emit(patterns, self.optics):
            v = ndimage.map_coordinates(em, [y.ravel(), x.ravel()], order=1, mode="nearest")
            out.append((v.reshape(x.shape) * self.ok).mean(axis=-1))
        return np.stack(out)
