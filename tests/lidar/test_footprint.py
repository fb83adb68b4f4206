"""Beam footprint: the cone's sampling map and the tilted-plane formula."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import FootprintOptions, cone_offsets, footprint_radius, tilted_plane_spread


def test_uniform_cone_fills_the_disk():
    o = FootprintOptions(divergence_rad=2e-3, profile="uniform")
    off = cone_offsets(np.random.default_rng(0).random((50_000, 2)), o)
    r = np.hypot(off[:, 0], off[:, 1])
    assert r.max() <= 1e-3
    assert np.mean(r < 0.5e-3) == pytest.approx(0.25, abs=0.01)  # area fraction
    assert off[:, 0].std() == pytest.approx(0.5e-3, rel=0.02)  # h / 2 per axis


def test_gaussian_cone_has_the_stated_sigma():
    o = FootprintOptions(divergence_rad=4e-3, profile="gaussian")
    off = cone_offsets(np.random.default_rng(1).random((100_000, 2)), o)
    assert o.sigma_rad == pytest.approx(1e-3)
    assert np.hypot(off[:, 0], off[:, 1]).max() <= 3e-3 * (1 + 1e-12)
    # the formula's per-axis spread is the samples' (truncation included)
    want = tilted_plane_spread(1.0, np.pi / 4, o)
    assert off[:, 0].std() == pytest.approx(want, rel=0.02)


def test_footprint_radius_and_spread_by_hand():
    o = FootprintOptions(divergence_rad=2e-3, profile="uniform")
    assert footprint_radius(50.0, o) == pytest.approx(50.0 * np.tan(1e-3))
    # 50 m at 60 deg incidence: 50 * tan(60) * 0.5 mrad
    assert tilted_plane_spread(50.0, np.pi / 3, o) == pytest.approx(50 * np.sqrt(3) * 5e-4)
    assert tilted_plane_spread(50.0, 0.0, o) == 0.0


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"divergence_rad": -1e-3}, "divergence_rad must be >= 0, got -0.001"),
        ({"divergence_rad": np.pi / 2}, "divergence_rad must be < 1.5708, got 1.57"),
        ({"divergence_rad": float("nan")}, "divergence_rad must be a finite number, got nan"),
        ({"profile": "tophat"}, "profile must be one of 'gaussian', 'uniform', got 'tophat'"),
        ({"samples": 0}, "samples must be >= 1, got 0"),
    ],
)
def test_footprint_options_refuse_bad_values(kw, match):
    with pytest.raises(ValueError, match=match):
        FootprintOptions(**kw)
    assert FootprintOptions(divergence_rad=0.0).sigma_rad == 0.0  # a single ray is valid
