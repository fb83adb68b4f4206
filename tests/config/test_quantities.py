"""Unit-bearing values, fractions and log-spaced densities."""

from __future__ import annotations

import math

import pytest

from simlunar.config.quantities import log_spaced, parse_fraction, parse_quantity


@pytest.mark.parametrize(
    ("value", "suffix", "expected"),
    [
        (30, "deg", 30.0),
        ("30", "deg", 30.0),
        ("30 deg", "deg", 30.0),
        ("30°", "deg", 30.0),
        (f"{math.pi / 2} rad", "deg", 90.0),
        ("20 cm", "m", 0.2),
        ("1.5km", "m", 1500.0),
        ("-2e-3 m", "m", -0.002),
    ],
)
def test_parse_quantity_converts_to_the_key_unit(value, suffix, expected):
    assert parse_quantity(value, suffix) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    ("value", "suffix", "match"),
    [
        ("30 furlong", "deg", "bad unit 'furlong'"),
        ("20 deg", "m", "bad unit 'deg' for a _m key"),
        ("abc", "m", "expected a number"),
        (True, "deg", "expected a number"),
        ([1], "deg", "expected a number"),
        ("1e400 m", "m", "finite"),
    ],
)
def test_parse_quantity_rejects(value, suffix, match):
    with pytest.raises(ValueError, match=match):
        parse_quantity(value, suffix)


def test_parse_fraction():
    assert parse_fraction("1/2048") == 1 / 2048
    assert parse_fraction(" 3/4 ") == 0.75
    assert parse_fraction(0.25) == 0.25
    assert parse_fraction(1) == 1.0
    for bad in ("0", "2/1", "1/0", "x", -0.5, True):
        with pytest.raises(ValueError):
            parse_fraction(bad)


def test_log_spaced_is_the_papers_powers_of_two():
    # paper, section 4.1: k/N = 1/2, 1/4, ..., 1/2048 (11 densities)
    d = log_spaced(0.5, 1 / 2048, 11)
    assert d == [2.0**-i for i in range(1, 12)]
    assert log_spaced(0.25, 0.25, 1) == [0.25]
    with pytest.raises(ValueError):
        log_spaced(0.5, 0.1, 0)
