"""A flash whose beam lights part of the view only (a 60 deg beam from 50 m over a 200 x 320 m
field lights 37 % of it): every rule relative to the flat frame's level must take the lit
part's level, not the whole frame's median (0 or the black's noise there)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.reconstruction.calibration import lit_level
from simlunar.reconstruction.shading import frame_noise
from simlunar.reconstruction.shadow import ShadowOptions, shadow_mask


def _disc_frame(rng, noise=0.03, black=0.0, shape=(200, 320), radius=70):
    """1 + noise inside a centred disc (about 24 % of the view), ``black`` outside."""
    r, c = np.indices(shape)
    disc = (r - shape[0] / 2) ** 2 + (c - shape[1] / 2) ** 2 < radius**2
    f = np.where(disc, 1.0 + rng.normal(0.0, noise, shape), black)
    return f, disc


def test_lit_level_is_the_median_of_the_lit_part():
    rng = np.random.default_rng(0)
    f, disc = _disc_frame(rng)
    assert float(np.median(f)) == 0.0  # the whole frame's median is the black
    # the lit part's interior (a window in from the beam's edge): the disc's median to its noise
    assert lit_level(f) == pytest.approx(float(np.median(f[disc])), abs=1e-3)
    # every pixel lit: the plain median, the same number to the bit
    g = 1.0 + rng.normal(0.0, 0.03, (50, 60))
    assert lit_level(g) == float(np.median(g))
    assert lit_level(np.zeros((4, 4))) == 0.0


def test_the_noise_of_a_partly_lit_frame_is_its_lit_part_s():
    # 3 % white noise on the disc: the estimate reads 0.03 (it was infinite: median 0)
    rng = np.random.default_rng(1)
    f, _ = _disc_frame(rng, noise=0.03)
    assert frame_noise(f) == pytest.approx(0.03, rel=0.05)


def test_the_black_outside_the_beam_is_not_taken_for_shadow():
    # a uniformly lit sun frame and a flash frame lit on a disc, its black outside the beam
    # only the read noise's faint floor: judged against the whole frame's median (that
    # floor) the black passed for lit, and the ratio sun / flash there made 24 % of the view
    # "shadow"; judged against the lit part's level the sun frame's own rule decides outside
    # the beam: no shadow anywhere
    rng = np.random.default_rng(2)
    flat, disc = _disc_frame(rng, noise=0.01, black=0.0)
    flat = np.where(disc, flat, np.abs(rng.normal(0.0, 2e-4, flat.shape)))
    sun = 0.5 + rng.normal(0.0, 0.005, flat.shape)
    mask = shadow_mask(sun, flat, options=ShadowOptions())
    assert mask.mean() < 1e-3


def test_a_frame_lit_everywhere_but_dominated_by_noise_is_lit_everywhere():
    # flash-on minus flash-off with a flash of 0.01 x the sun: mean 1, ~190 % per-pixel noise,
    # a third of the pixels under 2 % of the 99th percentile. Judged per pixel they were
    # "unlit": the level became the median of the bright ones (~1.6) and the noise estimate
    # fell by as much, so the flat was blurred too little and shading went below linear
    rng = np.random.default_rng(4)
    f = 1.0 + rng.normal(0.0, 1.9, (250, 400))
    assert lit_level(f) == float(np.median(f))
    assert frame_noise(f) == pytest.approx(1.9, rel=0.05)


def test_the_dark_side_of_a_beam_edge_is_not_lit():
    from simlunar.reconstruction.calibration import lit_mask

    rng = np.random.default_rng(5)
    f, disc = _disc_frame(rng, noise=0.5)  # a noisy disc: still lit as a whole
    lit = lit_mask(f)
    assert not (lit & ~disc).any()
    assert lit[disc].mean() > 0.6  # the disc less a band about a window wide at its edge
