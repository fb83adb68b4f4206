"""The preflight checks' own mathematics and file handling (hand-computed cases)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.errors import ConfigError
from simlunar.pipeline.preflight import _ray_box, check_study_sizes

LO, HI = np.array([0.0, -10.0, -1.0]), np.array([20.0, 0.0, 1.0])


@pytest.mark.parametrize(
    ("origin", "direction", "hits"),
    [
        ((10, -5, 30), (0, 0, -1), True),  # straight down into the box
        ((10, -5, 30), (0, 0, 1), False),  # straight up, away from it
        ((10, -5, 0), (0, 0, 1), True),  # starts inside the box
        ((-10, -5, 0), (1, 0, 0), True),  # parallel to z and y slabs, inside them, towards it
        ((-10, -5, 5), (1, 0, 0), False),  # parallel to the z slab but above it
        ((30, -5, 30), (0, 0, -1), False),  # beside the footprint
        ((-10, -5, 10), (1, 0, -0.5), True),  # oblique: reaches z = 1 at x = 8
        ((-10, -5, 10), (1, 0, -0.1), False),  # oblique: still at z = 7 at x = 20
    ],
)
def test_ray_box_by_hand(origin, direction, hits):
    o = np.array([origin], float)
    d = np.array([direction], float)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    assert bool(_ray_box(o, d, LO, HI)[0]) is hits


def test_density_sample_counts_are_checked_on_the_units_image():
    from types import SimpleNamespace

    study = SimpleNamespace(kind="sampling", densities=[0.5, 3 / 1000])
    cfg = SimpleNamespace(study=study)
    check_study_sizes(cfg, (40, 25))  # 1000 pixels: 3 samples, just enough
    study.densities = [0.5, 2.4 / 1000]  # rounds to 2
    with pytest.raises(ConfigError, match=r"study.densities\[1\]: density 0.0024 gives 2 samples"):
        check_study_sizes(cfg, (40, 25))
