"""The Delaunay border strip of a moving platform's samples, with and without the border
treatment (docs/lidar.md, "Reconstruction borders").

A grid plan (every ``step`` px, offset ``step / 2``) of a procedural terrain's heights at rest
samples exact cells; moving, each sample lands up to half a pixel off its cell (uniform, seeded;
its value the terrain there, bilinear), so the border rows are no longer collinear and the
Delaunay hull fills the border strip with slivers. Printed per density: the longest hull
triangle edge, and the MSE moving / rest of the linear reconstruction over the whole grid and
outside a 4 px border, with ``hull_edge_ratio`` 0 (the whole hull) and 3 (peeled), mean over
terrain seeds. No render: the mechanism alone, not the sensor.
Run: ``.venv/bin/python scripts/lidar_border_slivers.py``.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from simlunar.config.translate import preset_params
from simlunar.reconstruction.delaunay import reconstruct, triangulate
from simlunar.terrain import generate

SIZE, BORDER, SEEDS = 128, 4, (0, 1, 2, 3)


def _longest_edge(pts) -> float:
    t = triangulate(pts)
    e = [np.hypot(*(pts[t[:, i]] - pts[t[:, (i + 1) % 3]]).T) for i in range(3)]
    return float(np.max(e))


def _errors(truth, step: int, seed: int, ratio: float):
    r, c = np.mgrid[step // 2 : SIZE : step, step // 2 : SIZE : step]
    rest = np.column_stack([r.ravel(), c.ravel()]).astype(float)
    moved = rest + np.random.default_rng(seed).uniform(-0.5, 0.5, rest.shape)
    out = []
    for pts in (rest, moved):
        z = ndimage.map_coordinates(truth, pts.T, order=1, mode="nearest")
        err = (reconstruct(pts, z, truth.shape, hull_edge_ratio=ratio) - truth) ** 2
        inner = err[BORDER:-BORDER, BORDER:-BORDER]
        out.append((err.mean(), inner.mean()))
    return out, _longest_edge(moved)


def main() -> None:
    print("step  k     longest sliver (px)  MSE moving/rest: whole, interior (ratio 0 | ratio 3)")
    for step in (16, 8, 4):
        rows = {0.0: [], 3.0: []}
        longest = []
        for seed in SEEDS:
            terrain = generate(preset_params("aerial_1"), rng=seed, scale=0.25).terrain
            truth = terrain.heights[:SIZE, :SIZE]
            for ratio in rows:
                (rest, moved), edge = _errors(truth, step, seed, ratio)
                rows[ratio].append((moved[0] / rest[0], moved[1] / rest[1]))
            longest.append(edge)
        k = (SIZE // step) ** 2
        cells = " | ".join(
            "{:.2f}, {:.2f}".format(*np.mean(rows[x], axis=0)) for x in rows
        )
        print(f"{step:4d}  {k:4d}  {max(longest):8.1f}             {cells}")


if __name__ == "__main__":
    main()
