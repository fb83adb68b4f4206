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


@pytest.mark.parametrize("profile", ["gaussian", "uniform"])
@pytest.mark.parametrize("ratio", [0.5, 1.0, 1.4, 4.0])
def test_spot_in_field_is_the_sampled_spot_s_share(profile, ratio):
    # the closed form against the footprint's own sampler: the share of 200 000 sampled rays
    # whose offset lies inside the field's half-angle
    from simlunar.lidar.footprint import spot_in_field

    o = FootprintOptions(divergence_rad=1e-3, profile=profile)
    u = np.random.default_rng(0).random((200_000, 2))
    r = np.hypot(*cone_offsets(u, o).T)
    share = spot_in_field(ratio * 1e-3, o)
    assert share == pytest.approx(np.mean(r < 0.5 * ratio * 1e-3), abs=3e-3)
    if profile == "gaussian" and ratio == 1.0:
        # the rover preset's 1 mrad beam in its 1 mrad field: 1 - e^-2 of the untruncated
        # beam (a receiver that saw the whole spot read +16 % signal: 1 / 0.865)
        assert share == pytest.approx((1 - np.exp(-2.0)) / (1 - np.exp(-4.5)), rel=1e-12)
        assert 1 / share == pytest.approx(1.146, abs=0.01)


def test_a_steered_beam_s_field_clip_scales_its_signal():
    from simlunar.lidar.footprint import spot_in_field
    from simlunar.lidar.hardware import INSTRUMENTS
    from simlunar.lidar.scan import SteeredBeamOptions, _beam_detector, with_hardware

    class _Sun:
        sun_irradiance = 1.0

    hw = INSTRUMENTS["rover_mast_scanner"]
    ideal = with_hardware(SteeredBeamOptions(), hw)
    clipped = with_hardware(SteeredBeamOptions(field_clip=True), hw)
    a, b = _beam_detector(_Sun, ideal), _beam_detector(_Sun, clipped)
    share = spot_in_field(hw.field_rad, clipped.footprint)
    assert b.signal_photons == pytest.approx(share * a.signal_photons, rel=1e-12)
    assert share < 0.9 and b.background_photons_per_s == a.background_photons_per_s
    # LOLA's 400 urad field holds its 100 urad beam whole
    lola = with_hardware(SteeredBeamOptions(field_clip=True), INSTRUMENTS["lola_beam"])
    assert _beam_detector(_Sun, lola).signal_photons == pytest.approx(
        _beam_detector(
            _Sun, with_hardware(SteeredBeamOptions(), INSTRUMENTS["lola_beam"])
        ).signal_photons
    )
