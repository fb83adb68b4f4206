"""Crater profiles (Pike 1977), degradation by diffusion, superposition order."""

import numpy as np
import pytest

from simlunar.terrain.craters import (
    S_MAX,
    Crater,
    crater_profile,
    fresh_depth,
    fresh_rim_height,
    place_craters,
    stamp_craters,
)


def _one(d, s=0.0, x=50.0, y=-50.0, age=0.0):
    prof = crater_profile(np.array([0.0, 1.0]), d, s)
    return Crater(x, y, d, prof[1] - prof[0], prof[1], age, s, s <= S_MAX)


def test_pike_formulas_hand_values():
    # Pike 1977: d = 0.196 D^1.01, h = 0.036 D^1.014; for D = 10 m: 2.0069 m and 0.37195 m
    assert fresh_depth(10.0) == pytest.approx(0.196 * 10**1.01) == pytest.approx(2.005654, rel=1e-5)
    assert fresh_rim_height(10.0) == pytest.approx(0.036 * 10**1.014)
    assert fresh_rim_height(10.0) == pytest.approx(0.371794, rel=1e-5)


@pytest.mark.parametrize("diameter", [4.0, 20.0])
def test_isolated_fresh_crater_on_a_plane_has_pike_depth_and_rim(diameter):
    spacing = diameter / 200  # 100 cells per radius: the rim crest is sampled within 1 %
    n = 1001
    h = np.zeros((n, n))
    x0 = 0.0
    cx = (n / 2) * spacing  # centre on cell (500, 500)
    c = _one(diameter, x=cx, y=-cx)
    stamp_craters(h, [c], spacing=spacing, origin=(x0, 0.0))
    depth = h.max() - h.min()
    # rim crest to floor / D, and rim height above the undisturbed plane
    assert depth / diameter == pytest.approx(fresh_depth(diameter) / diameter, rel=1e-3)
    assert h.max() == pytest.approx(fresh_rim_height(diameter), rel=1e-3)
    assert h[500, 500] == pytest.approx(
        fresh_rim_height(diameter) - fresh_depth(diameter), rel=1e-6
    )
    # rim at distance R from the centre; plane untouched beyond the ejecta (3 R)
    r, col = np.unravel_index(np.argmax(h), h.shape)
    assert np.hypot(r - 500, col - 500) * spacing == pytest.approx(diameter / 2, abs=1.5 * spacing)
    assert h[500, 500 + 350] == 0.0 and h[0, 0] == 0.0
    # ejecta thickness decays with distance
    assert h[500, 500 + 120] > h[500, 500 + 150] > h[500, 500 + 250] > 0


def test_degradation_makes_craters_shallower_and_softer():
    r = np.linspace(0, 4, 401)
    fresh = crater_profile(r, 10.0, 0.0)
    old = crater_profile(r, 10.0, 0.5)
    older = crater_profile(r, 10.0, 0.9)
    relief = [p.max() - p.min() for p in (fresh, old, older)]
    assert relief[0] > relief[1] > relief[2] > 0
    slope = [np.abs(np.diff(p)).max() for p in (fresh, old, older)]
    assert slope[0] > slope[1] > slope[2]
    # diffusion conserves volume: the integral of z over the plane (2 pi r dr) is unchanged
    rr = np.linspace(0, 7, 1401)
    v0 = np.trapezoid(crater_profile(rr, 10.0, 0.0) * 2 * np.pi * rr, rr)
    v1 = np.trapezoid(crater_profile(rr, 10.0, 0.5) * 2 * np.pi * rr, rr)
    scale = np.trapezoid(np.abs(crater_profile(rr, 10.0, 0.0)) * 2 * np.pi * rr, rr)
    assert abs(v1 - v0) < 0.01 * scale


def test_younger_crater_cuts_the_older_one():
    spacing = 0.05
    big = _one(20.0, x=25.0, y=-25.0)
    small = _one(2.0, x=25.0, y=-25.0)
    a = np.zeros((1000, 1000))
    b = np.zeros((1000, 1000))
    stamp_craters(a, [small, big], spacing=spacing, origin=(0.0, 0.0))  # big is younger
    stamp_craters(b, [big, small], spacing=spacing, origin=(0.0, 0.0))  # small is younger
    ref = np.zeros((1000, 1000))
    stamp_craters(ref, [big], spacing=spacing, origin=(0.0, 0.0))
    win = np.s_[480:520, 480:520]
    # the young big crater erased the small one at its centre (bowl weight 1 - r^2 ~ 1)
    assert np.abs(a[win] - ref[win]).max() < 0.02 * fresh_depth(2.0)
    # the young small crater survives inside the big one with its full depth; its erase flattens
    # the big bowl's curvature under it (d_big (R_small / R_big)^2 ~ 0.04 m) towards the mean,
    # hence the 0.03 m margin
    floor = fresh_rim_height(2.0) - fresh_depth(2.0)
    assert (b[win] - ref[win]).min() == pytest.approx(floor, abs=0.03)
    assert np.abs(b[win] - ref[win]).max() > 0.9 * abs(floor)


def test_placement_sorted_oldest_first_with_visible_degradation():
    d = np.full(2000, 10.0)
    cs = place_craters(d, extent=(0, 100, -100, 0), diffusivity=5.5, max_age_myr=1000.0, rng=1)
    ages = np.array([c.age_myr for c in cs])
    assert np.all(np.diff(ages) <= 0)
    # each crater age is uniform over its visible lifetime (S_MAX R)^2 / (2 kappa)
    life = (S_MAX * 5.0) ** 2 / (2 * 5.5)
    assert ages.max() <= life and ages.mean() == pytest.approx(life / 2, rel=0.05)
    assert all(c.visible for c in cs)
    xs = np.array([c.x for c in cs])
    assert 0 <= xs.min() and xs.max() <= 100
    young = place_craters(d, extent=(0, 100, -100, 0), diffusivity=5.5, max_age_myr=0.1, rng=1)
    assert max(c.age_myr for c in young) <= 0.1
    assert np.mean([c.depth for c in young]) > np.mean([c.depth for c in cs])
