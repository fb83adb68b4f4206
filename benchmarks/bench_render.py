"""Rendering benchmarks (see ``benchmarks/run.py``).

``pattern_swap``: 20 projector patterns on one terrain view, rendered by rebuilding the
Mitsuba scene for every pattern (reference) versus by swapping the projector texture through
``mi.traverse`` in one :class:`~simlunar.render.scene.TerrainScene` (ours). Reports the JIT
kernels compiled after the first pattern (``kernel_compiles``, target 0), counted with Dr.Jit's
kernel history: a launched JIT kernel whose ``cache_hit`` is false was compiled.
"""

from __future__ import annotations

import time

import numpy as np

N_PATTERNS = 20
SHAPE = (256, 256)  # terrain cells and camera pixels
PROJ = (192, 256)  # projector pattern (rows, cols)
SPP = 4


def _setup(shape=SHAPE, proj_shape=PROJ, n_patterns=N_PATTERNS):
    from scipy.ndimage import gaussian_filter

    from simlunar.geometry import Camera, Intrinsics, Pose, Projector
    from simlunar.terrain.types import Terrain

    rng = np.random.default_rng(2024)
    h = gaussian_filter(rng.normal(size=shape), 6.0)
    h *= 1.5 / np.abs(h).max()
    spacing = 0.05 * SHAPE[0] / shape[0]  # the same 12.8 m square at any grid size
    t = Terrain(
        h,
        np.full(shape, 0.15, np.float32),
        spacing,
        origin=(-shape[1] * spacing / 2, shape[0] * spacing / 2),
    )
    cam = Camera(
        Intrinsics.from_fov(shape[1], shape[0], 45.0),
        Pose.look_at([0.6, 0.0, 12.0], [0.0, 0.0, 0.0]),
    )
    proj = Projector(
        Intrinsics.from_fov(proj_shape[1], proj_shape[0], 45.0),
        Pose.look_at([-0.6, 0.0, 12.0], [0.0, 0.0, 0.0]),
    )
    # gray-code-like stripes of decreasing period
    cols = np.arange(proj_shape[1])
    pats = np.stack(
        [
            np.broadcast_to(((cols >> (k % 8)) & 1).astype(np.float32), proj_shape)
            for k in range(n_patterns)
        ]
    )
    return t, cam, proj, pats


def _jit_compiles(history) -> int:
    import drjit as dr

    return sum(
        1 for e in history if e.get("type") == dr.KernelType.JIT and not e.get("cache_hit", 0)
    )


def pattern_swap(*, smoke: bool = False) -> dict:
    """Rebuild vs texture swap (``smoke``: 4 patterns, a 32 x 32 view, 1 spp)."""
    from simlunar.render import backend
    from simlunar.render.lights import ProjectorLight
    from simlunar.render.scene import TerrainScene, luminance

    backend.init()
    import drjit as dr

    if smoke:
        shape, proj_shape, n_patterns, spp = (32, 32), (24, 32), 4, 1
    else:
        shape, proj_shape, n_patterns, spp = SHAPE, PROJ, N_PATTERNS, SPP
    t, cam, proj, pats = _setup(shape, proj_shape, n_patterns)

    def build(p):
        return TerrainScene(t, cam, lights=[ProjectorLight(proj, p)], max_depth=2, spp=spp)

    # warm-up (kernel cache, allocator) so neither path pays the first compile
    build(pats[0]).render()

    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # clears
        t0 = time.perf_counter()
        ref = [luminance(build(p).render()) for p in pats]
        reference_s = time.perf_counter() - t0
        ref_compiles = _jit_compiles(dr.kernel_history())

        t0 = time.perf_counter()
        scene = build(pats[0])
        ours = [luminance(scene.render())]
        first_hist = dr.kernel_history()
        for p in pats[1:]:
            scene.set_pattern(p)
            ours.append(luminance(scene.render()))
        ours_s = time.perf_counter() - t0
        later = dr.kernel_history()
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    n_jit = sum(1 for e in later if e.get("type") == dr.KernelType.JIT)
    return {
        "reference_s": round(reference_s, 4),
        "ours_s": round(ours_s, 4),
        "smoke": smoke,
        "patterns": n_patterns,
        "resolution": f"{shape[1]}x{shape[0]}",
        "spp": spp,
        "kernel_compiles": _jit_compiles(later),
        "kernel_compiles_first_pattern": _jit_compiles(first_hist),
        "kernel_launches_after_first": n_jit,
        "reference_kernel_compiles": ref_compiles,
        "max_abs_diff": float(np.max(np.abs(np.stack(ref) - np.stack(ours)))),
    }


BENCHMARKS = {"pattern_swap": pattern_swap}
