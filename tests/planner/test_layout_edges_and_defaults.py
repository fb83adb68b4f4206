"""Where the lloyd placement puts sites at the image edges, and what its documented default
density power is."""

from __future__ import annotations

import numpy as np

from simlunar.planner.placement import LloydOptions, _snap, lloyd_layout


def test_sites_snapped_onto_the_far_edges_lie_on_the_last_row_and_column():
    """On a 10 x 12 grid with a pitch of 2 px and a band of 0.75 pitch (1.5 px), a site 1 px
    from an edge goes onto it: row 0, row 9 (rows - 1), column 0, column 11 (cols - 1), the
    centres of the grid's edge cells, never one past them. A site 1.5 px or more from every
    edge stays."""
    sr = np.array([1.0, 8.0, 5.0, 5.0, 4.0])
    sc = np.array([6.0, 6.0, 1.0, 10.0, 1.5])
    _snap(sr, sc, np.full(5, 2.0), (10, 12), 0.75)
    np.testing.assert_array_equal(sr, [0.0, 9.0, 5.0, 5.0, 4.0])
    np.testing.assert_array_equal(sc, [6.0, 6.0, 0.0, 11.0, 1.5])


def test_the_lloyd_layout_of_a_map_defaults_to_the_square_root_of_the_map():
    """``density_power`` left out is 1/2 for lloyd (a 2-D CVT of weight density^2 follows the
    density): the layout of a map without the option is the layout with 0.5 given, and
    differs from the layout at power 1.5 on a map with structure."""
    weights = np.random.default_rng(1).random((24, 32)) ** 3
    weights[:, :8] *= 20.0
    default = lloyd_layout(weights, 60, rng=np.random.default_rng(7), options=LloydOptions())
    half = lloyd_layout(
        weights, 60, rng=np.random.default_rng(7), options=LloydOptions(density_power=0.5)
    )
    steeper = lloyd_layout(
        weights, 60, rng=np.random.default_rng(7), options=LloydOptions(density_power=1.5)
    )
    np.testing.assert_array_equal(default, half)
    assert not np.array_equal(default, steeper)
