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


def test_refine_is_exact_on_a_plane_and_keeps_the_extent():
    # a tilted plane z = 0.5 x + 0.25 y on 2 m cells, refined to 0.5 m: bilinear interpolation
    # between cell centres is exact for a plane (inside the outer half cell, which is clamped)
    from simlunar.terrain.generate import refine
    from simlunar.terrain.types import Terrain

    rows, cols, sp = 10, 12, 2.0
    x0, y0 = -6.0, 4.0
    xc = x0 + (np.arange(cols) + 0.5) * sp
    yc = y0 - (np.arange(rows) + 0.5) * sp
    h = 0.5 * xc[None, :] + 0.25 * yc[:, None]
    t = refine(Terrain(h, np.full(h.shape, 0.1, np.float32), sp, (x0, y0)), 0.5)
    assert t.shape == (40, 48) and t.spacing == 0.5 and t.origin == (x0, y0)
    xf = x0 + (np.arange(48) + 0.5) * 0.5
    yf = y0 - (np.arange(40) + 0.5) * 0.5
    want = 0.5 * xf[None, :] + 0.25 * yf[:, None]
    inner = (slice(2, -2), slice(2, -2))
    assert np.allclose(t.heights[inner], want[inner], atol=1e-12)
    assert np.allclose(t.albedo, 0.1)
    with pytest.raises(ValueError, match="finer"):
        refine(Terrain(h, np.ones_like(h, np.float32), sp, (x0, y0)), 3.0)


def test_add_rocks_stamps_the_generator_s_rocks_on_a_given_surface():
    # rocks of a Golombek population on a flat surface: the same seed the same rocks, the
    # surface itself untouched, every raised cell a rock's and brighter by its contrast
    from simlunar.terrain.generate import add_rocks
    from simlunar.terrain.params import RockParams
    from simlunar.terrain.types import Terrain

    rocks = RockParams(law="golombek", coefficient=0.07, d_min=0.2, d_max=2.0, albedo_contrast=0.5)
    flat = Terrain(np.zeros((200, 200)), np.full((200, 200), 0.12, np.float32), 0.1, (0.0, 20.0))
    a, placed = add_rocks(flat, rocks, rng=5)
    b, _ = add_rocks(flat, rocks, rng=5)
    assert np.array_equal(a.heights, b.heights) and len(placed) > 10
    assert np.array_equal(flat.heights, np.zeros((200, 200)))  # the input is left alone
    raised = a.heights > 1e-9
    assert raised.any() and (a.heights >= 0).all()
    # the rocks' albedo contrast only where they stand
    assert np.allclose(a.albedo[~raised], 0.12) and (a.albedo[raised] > 0.12).mean() > 0.5
    # disabled rocks: the terrain itself
    off = RockParams(enabled=False)
    assert add_rocks(flat, off, rng=1) == (flat, [])
