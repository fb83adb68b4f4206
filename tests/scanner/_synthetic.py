"""A NumPy structured-light 'renderer' for planes: exact, fast, independent of Mitsuba.

Each camera pixel is split into ``ss x ss`` sub-rays; each hits the plane ``n . X = d`` and
picks up the projector pattern value at its projector pixel (nearest, as Mitsuba's projector
texture with ``filter_type='nearest'``) times the albedo. No shading, no interreflection.
"""

from __future__ import annotations

import numpy as np


class PlaneCapture:
    def __init__(self, rig, normal, offset, *, ss=3, albedo=0.8, noise=0.0, rng=0):
        self.rig = rig
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
        self.albedo = albedo

    def intersect(self, cam, uv):
        o, d = cam.rays(uv)
        t = (self.offset - o @ self.normal) / (d @ self.normal)
        return o + t[..., None] * d

    def true_depth(self, cam):
        X = self.intersect(cam, cam.pixel_centers())
        return cam.pose.world_to_device(X)[..., 2]

    def render(self, patterns):
        patterns = np.asarray(patterns, float)
        self.renders += len(patterns)
        vals = patterns[:, self.pr, self.pc] * self.ok[None]
        return self.albedo * vals.mean(axis=-1)

    def sense(self, images):
        images = np.asarray(images, float)
        if self.noise > 0:
            images = images + self.rng.normal(0, self.noise, images.shape)
        return images
