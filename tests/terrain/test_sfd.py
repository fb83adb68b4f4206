"""Size-frequency laws: the sampled populations follow the requested cumulative law."""

import numpy as np
import pytest

from simlunar.terrain import sfd


def _loglog_slope(d, d_lo, d_hi, n_dmax_total):
    """Slope of log N(>D) vs log D from a sample, after removing the truncation at d_max."""
    grid = np.geomspace(d_lo, d_hi, 10)
    cum = np.array([(d > g).sum() for g in grid]) - n_dmax_total
    return np.polyfit(np.log(grid), np.log(cum), 1)[0], grid, cum


@pytest.mark.parametrize(
    ("kind", "name", "exponent", "area", "d_min", "d_max"),
    [
        ("craters", "trask", 2.0, 1e6, 1.0, 1000.0),
        ("rocks", "intercrater", 1.75457, 5e8, 0.5, 500.0),
        ("rocks", "viper", 2.482, 2e6, 0.2, 200.0),
        ("rocks", "high_blockiness", 2.6607, 1e6, 0.3, 300.0),
    ],
)
def test_power_law_populations_have_the_stated_slope_and_density(
    kind, name, exponent, area, d_min, d_max
):
    law = sfd.get_law(kind, name)
    d = sfd.sample_diameters(law, area, d_min, d_max, rng=7)
    expected = sfd.expected_count(law, area, d_min, d_max)
    assert expected > 20_000  # large sample: Poisson sd < 0.7 %
    # total count: Poisson, 4 sd margin
    assert abs(d.size - expected) < 4 * np.sqrt(expected)
    assert d.min() >= d_min and d.max() <= d_max
    # maximum-likelihood exponent of a Pareto tail (truncation at 1000 d_min is negligible):
    # b = n / sum(log(D / d_min)), sd = b / sqrt(n) (~0.015 here); 4 sd margin
    b = d.size / np.log(d / d_min).sum()
    assert b == pytest.approx(exponent, abs=4 * exponent / np.sqrt(d.size))
    # least-squares slope of log N(>D) over the range where N(>D) >= 1000; its spread over
    # 30 seeds is sd ~0.023, so a 0.1 margin
    d_hi = d_min * (d.size / 1000) ** (1 / exponent)
    slope, grid, cum = _loglog_slope(d, d_min, d_hi, 0)
    assert slope == pytest.approx(-exponent, abs=0.1)
    # cumulative density at each grid diameter within 4 Poisson sd of area * (N(D) - N(d_max))
    want = area * (law(grid) - law(d_max))
    assert np.all(np.abs(cum - want) < 4 * np.sqrt(want) + 1)


def test_viper_crater_law_switches_slope_at_80_m():
    law = sfd.get_law("craters", "viper")
    # hand values: 29174 * 10^-1.92 / 1e6 and 156228 * 100^-2.389 / 1e6 (per m^2)
    assert law(10.0) == pytest.approx(29174 * 10**-1.92 * 1e-6)
    assert law(100.0) == pytest.approx(156228 * 100**-2.389 * 1e-6)
    area = 4e9  # 4000 km^2: ~2000 craters above 80 m
    d = sfd.sample_diameters(law, area, 20.0, 2000.0, rng=3)
    small, *_ = _loglog_slope(d, 20.0, 70.0, 0)
    large, *_ = _loglog_slope(d, 90.0, 300.0, 0)
    assert small == pytest.approx(-1.92, abs=0.07)
    assert large == pytest.approx(-2.389, abs=0.12)


def test_plain_power_law_with_user_exponent():
    law = sfd.get_law("craters", "power", coefficient=0.5, exponent=3.0)
    assert law(2.0) == pytest.approx(0.5 / 8)
    d = sfd.sample_diameters(law, 1e5, 1.0, 100.0, rng=1)
    # MLE of a (nearly untruncated) Pareto exponent: n / sum(log(D / d_min)); sd = b / sqrt(n)
    b = d.size / np.log(d / 1.0).sum()
    assert b == pytest.approx(3.0, abs=4 * 3.0 / np.sqrt(d.size))


def test_same_seed_same_sample():
    law = sfd.get_law("craters", "trask")
    a = sfd.sample_diameters(law, 1e4, 1.0, 10.0, rng=5)
    b = sfd.sample_diameters(law, 1e4, 1.0, 10.0, rng=5)
    c = sfd.sample_diameters(law, 1e4, 1.0, 10.0, rng=6)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_errors_name_the_law_or_field():
    with pytest.raises(ValueError, match=r"unknown craters law 'moon'.*power.*trask.*viper"):
        sfd.get_law("craters", "moon")
    with pytest.raises(ValueError, match=r"high_blockiness"):
        sfd.get_law("rocks", "nope")
    with pytest.raises(ValueError, match="exponent"):
        sfd.get_law("rocks", "power", coefficient=1.0)
    with pytest.raises(ValueError, match="takes no parameters"):
        sfd.get_law("craters", "trask", exponent=2.0)
    law = sfd.get_law("craters", "trask")
    with pytest.raises(ValueError, match="range is empty"):
        sfd.sample_diameters(law, 1.0, 5.0, 5.0, rng=0)
    with pytest.raises(ValueError, match="d_min_m"):
        sfd.sample_diameters(law, 1.0, -1.0, 5.0, rng=0)


# ---- the Golombek & Rapp (1997) cumulative fractional area model ---------------------------


def test_golombek_number_density_integrates_to_its_area_fraction():
    from scipy.integrate import quad

    from simlunar.terrain.sfd import golombek_rocks

    k = 0.07
    q = 1.79 + 0.152 / k
    for d in (0.1, 0.3, 1.0):
        # N(>D) against a quadrature of n(x) = (4 k q / pi) exp(-q x) / x^2
        n_num = quad(lambda x: 4 * k * q / np.pi * np.exp(-q * x) / x**2, d, np.inf)[0]
        assert golombek_rocks(np.array(d), k=k) == pytest.approx(n_num, rel=1e-8)

        # the area of the rocks larger than D: F_k(D) = k exp(-q D), from N alone
        def rock_area_density(x, h=1e-5 * d):  # pi x^2 / 4 n(x), n = -dN/dx numerically
            return (
                np.pi
                * x**2
                / 4
                * (golombek_rocks(x - h, k=k) - golombek_rocks(x + h, k=k))
                / (2 * h)
            )

        area = quad(rock_area_density, d, 60.0, limit=200)[0]
        assert area == pytest.approx(k * np.exp(-q * d), rel=1e-5)


def test_golombek_sampled_population_covers_its_area_fraction():
    from simlunar.terrain.sfd import get_law, sample_diameters

    k, area = 0.05, 4.0e4
    q = 1.79 + 0.152 / k
    law = get_law("rocks", "golombek", coefficient=k)
    d = sample_diameters(law, area, 0.1, 3.0, rng=3)
    covered = np.sum(np.pi * d**2 / 4) / area
    expected = k * (np.exp(-q * 0.1) - np.exp(-q * 3.0))
    assert covered == pytest.approx(expected, rel=0.05)


@pytest.mark.parametrize(
    "params, match",
    [({}, "area fraction"), ({"coefficient": 1.5}, "area fraction"),
     ({"coefficient": 0.05, "exponent": 2.0}, "no exponent")],
)  # fmt: skip
def test_golombek_parameters_checked(params, match):
    from simlunar.terrain.sfd import get_law

    with pytest.raises(ValueError, match=match):
        get_law("rocks", "golombek", **params)
