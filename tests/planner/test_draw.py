"""The paper's weighted random draw (the ``random`` placement): its options' bounds, a draw
proportional to the map, and the uniform share."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.planner.draw import RandomDrawOptions, weighted_draw


def test_draw_follows_the_map():
    # two halves weighted 3 : 1, k small against N: the share of samples follows the weights
    w = np.ones((40, 40))
    w[:, :20] = 3.0
    left = [(weighted_draw(w, 40, rng=np.random.default_rng(s), options=RandomDrawOptions()) % 40
             < 20).mean() for s in range(200)]  # fmt: skip
    assert np.mean(left) == pytest.approx(0.75, abs=0.02)


def test_zero_weights_are_drawn_last_and_a_full_mix_is_uniform():
    w = np.zeros((10, 10))
    w[:5] = 1.0
    flat = weighted_draw(w, 50, rng=np.random.default_rng(0), options=RandomDrawOptions())
    assert set(flat.tolist()) == set(range(50))
    mixed = RandomDrawOptions(uniform_mix=1.0)
    lows = [(weighted_draw(w, 10, rng=np.random.default_rng(s), options=mixed) >= 50).mean()
            for s in range(200)]  # fmt: skip
    assert np.mean(lows) == pytest.approx(0.5, abs=0.03)


def test_power_one_leaves_the_stream_untouched():
    w = np.random.default_rng(3).random((20, 30))
    a = weighted_draw(w, 25, rng=np.random.default_rng(1), options=RandomDrawOptions())
    b = weighted_draw(
        w, 25, rng=np.random.default_rng(1), options=RandomDrawOptions(density_power=1)
    )
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(
    ("opts", "match"),
    [({"uniform_mix": 1.5}, "uniform_mix must be <= 1"), ({"density_cap": 0.5}, "density_cap must be >= 1"),
     ({"blue_noise_radius": 0.0}, "blue_noise_radius must be > 0"), ({"cap_block": 0}, "cap_block must be >= 1"),
     ({"density_power": -1.0}, "density_power must be > 0")],
)  # fmt: skip
def test_bounds_are_the_options_own(opts, match):
    with pytest.raises(ValueError, match=match):
        RandomDrawOptions(**opts)
