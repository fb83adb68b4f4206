"""Rocks raise the DEM, carry their albedo, and cluster."""

import numpy as np
import pytest

from simlunar.terrain.rocks import Rock, place_rocks, stamp_rocks


def test_rock_raises_dem_by_its_height_inside_its_footprint():
    h = np.zeros((200, 200))
    fac = np.ones((200, 200))
    rk = Rock(
        x=10.0,
        y=-10.0,
        diameter=4.0,
        height=1.5,
        elongation=1.0,
        orientation=0.0,
        albedo_factor=1.2,
    )
    stamp_rocks(h, fac, [rk], spacing=0.1, origin=(0.0, 0.0), rng=0)
    assert h.min() == 0.0  # never lowers the ground
    assert h.max() == pytest.approx(1.5, rel=1e-3)  # top at the centre cell (10, -10)
    r, c = np.unravel_index(np.argmax(h), h.shape)
    assert abs(r - 99.5) <= 1 and abs(c - 99.5) <= 1
    raised = h > 0
    # footprint area about pi * 2^2 = 12.6 m^2 (irregular outline: within 30 %)
    assert raised.sum() * 0.01 == pytest.approx(np.pi * 4, rel=0.3)
    assert np.all(fac[raised] == 1.2) and np.all(fac[~raised] == 1.0)
    assert h[0, 0] == 0.0 and h[-1, -1] == 0.0


def test_rock_sits_on_the_lowest_ground_of_its_footprint():
    h = np.tile(np.linspace(0, 1, 100), (100, 1))  # a slope in x
    fac = np.ones_like(h)
    rk = Rock(5.0, -5.0, 2.0, 0.5, 1.0, 0.0, 1.0)
    stamp_rocks(h, fac, [rk], spacing=0.1, origin=(0.0, 0.0), rng=0)
    assert np.all(h >= np.tile(np.linspace(0, 1, 100), (100, 1)))
    # footprint spans x in [4, 6] m = columns 40..59 (ground 40/99..59/99): the top is the
    # lowest footprint ground plus the rock height, not the highest
    assert h[:, 35:65].max() == pytest.approx(40 / 99 + 0.5, abs=0.03)


def _quadrat_dispersion(rocks, size=100.0, n=10):
    xs = np.array([r.x for r in rocks])
    ys = np.array([r.y for r in rocks])
    counts, *_ = np.histogram2d(xs, ys, bins=n, range=[[0, size], [-size, 0]])
    return counts.var() / counts.mean()


def test_clustered_placement_is_overdispersed_and_uniform_is_poisson():
    d = np.full(3000, 1.0)
    ext = (0.0, 100.0, -100.0, 0.0)
    kw = dict(extent=ext, cluster_radius_m=2.0, mean_per_cluster=20.0, albedo_contrast=0.1)
    uni = place_rocks(d, cluster_fraction=0.0, rng=1, **kw)
    clu = place_rocks(d, cluster_fraction=0.9, rng=1, **kw)
    # quadrat counts: variance / mean = 1 for a Poisson process (sd ~ sqrt(2/99) = 0.14)
    assert _quadrat_dispersion(uni) == pytest.approx(1.0, abs=0.5)
    assert _quadrat_dispersion(clu) > 5.0
    for rocks in (uni, clu):
        xs = np.array([r.x for r in rocks])
        ys = np.array([r.y for r in rocks])
        assert xs.min() >= 0 and xs.max() <= 100 and ys.min() >= -100 and ys.max() <= 0
    heights = np.array([r.height for r in uni])
    assert heights.min() >= 0.25 and heights.max() <= 0.5  # half-buried, D = 1
    assert np.mean([r.albedo_factor for r in uni]) == pytest.approx(1.1, abs=0.01)
