"""The ideal Dirac sampler: the true depth at the planned pixels, seeded Gaussian range noise of
the given standard deviation, its input checks."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.sensors.ideal import IdealOptions, IdealSampler

TRUTH = np.arange(12.0).reshape(3, 4)  # depth r * 4 + c


def test_reads_the_truth_at_the_planned_pixels():
    rc = np.array([[0, 0], [2, 3], [1, 2]])
    a = IdealSampler(TRUTH).acquire(rc)
    np.testing.assert_array_equal(a.values, [0.0, 11.0, 6.0])
    np.testing.assert_array_equal(a.rc, rc)
    assert a.shape == (3, 4) and a.frames == 0 and a.seconds == 0.0


def test_range_noise_is_seeded_with_the_given_std():
    s = IdealSampler(np.zeros((100, 100)), IdealOptions(range_noise_std=0.05))
    rc = np.stack(np.unravel_index(np.arange(10_000), (100, 100)), axis=-1)
    a = s.acquire(rc, rng=3)
    b = s.acquire(rc, rng=3)
    np.testing.assert_array_equal(a.values, b.values)
    assert not np.array_equal(a.values, s.acquire(rc, rng=4).values)
    # the sample std of 10 000 normal draws is within 3 % of sigma (std error ~ 0.7 %)
    assert a.values.std() == pytest.approx(0.05, rel=0.03)
    assert abs(a.values.mean()) < 4 * 0.05 / 100


def test_no_noise_without_a_std_even_with_an_rng():
    a = IdealSampler(TRUTH).acquire(np.array([[1, 1]]), rng=0)
    assert a.values.tolist() == [5.0]


@pytest.mark.parametrize(
    ("truth", "message"),
    [
        (np.zeros(4), r"^truth must have shape \(rows, cols\), got \(4,\)$"),
        (np.array([[0.0, np.nan]]), "^truth contains NaN or infinite values$"),
    ],
)
def test_bad_truth(truth, message):
    with pytest.raises(ValueError, match=message):
        IdealSampler(truth)


def test_bad_options_and_a_missing_plan():
    with pytest.raises(ValueError, match=r"^range_noise_std must be >= 0, got -0\.1$"):
        IdealOptions(range_noise_std=-0.1)
    with pytest.raises(ValueError, match=r"^range_noise_std must be a finite number, got nan$"):
        IdealOptions(range_noise_std=float("nan"))
    with pytest.raises(
        ValueError, match=r"^the ideal sampler measures planned pixels: rc is required$"
    ):
        IdealSampler(TRUTH).acquire(None)
