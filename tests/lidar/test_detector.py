"""Photon counting: Poisson shot noise with the rendered mean, pile-up, Coates."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from simlunar.lidar import (
    DetectorOptions,
    TimeBins,
    coates_correction,
    expected_counts,
    photon_counts,
    photon_counts_dead_time,
)

BINS = TimeBins(start_opl=90.0, bin_opl=0.3, count=40)


def test_expected_counts_adds_sun_per_bin_and_dark_counts():
    sig = np.zeros((2, BINS.count))
    sig[0, 10] = 2.0
    opts = DetectorOptions(
        signal_photons=50.0, background_photons_per_s=1e9, dark_count_rate_hz=1e6
    )
    lam = expected_counts(sig, np.array([0.5, 0.0]), BINS, opts)
    per_bin = (0.5 * 1e9 + 1e6) * BINS.bin_s  # sun radiance * scale * bin duration
    assert lam[0, 0] == pytest.approx(per_bin)
    assert lam[0, 10] == pytest.approx(100.0 + per_bin)
    assert lam[1, 5] == pytest.approx(1e6 * BINS.bin_s)


def test_counts_are_poisson_with_the_rendered_mean():
    # dispersion test: for Poisson, sum (x - m)^2 / m over N draws is chi^2 with N dof
    mean = np.full(20_000, 3.7)
    x = photon_counts(mean, options=DetectorOptions(pulses=1), rng=1)
    d = np.sum((x - 3.7) ** 2 / 3.7)
    p = stats.chi2.sf(d, df=x.size)
    assert 0.001 < p < 0.999
    assert x.mean() == pytest.approx(3.7, rel=0.02)
    # pulses accumulate: mean and variance scale with their number
    y = photon_counts(np.full(20_000, 0.2), options=DetectorOptions(pulses=10), rng=2)
    assert y.mean() == pytest.approx(2.0, rel=0.03)
    assert y.var() == pytest.approx(2.0, rel=0.05)


def test_first_photon_receiver_piles_up_and_coates_undoes_it():
    lam = np.zeros(BINS.count)
    lam[:] = 0.02
    lam[20] = 1.0  # strong return
    opts = DetectorOptions(pulses=20_000, dead_time_s=np.inf)
    h = photon_counts(np.broadcast_to(lam, (4, BINS.count)), options=opts, rng=3)
    assert (h.sum(axis=1) <= opts.pulses).all()
    # early bins see every armed pulse, late bins are starved after the strong return
    assert h[:, 25:].mean() < 0.5 * h[:, :15].mean()
    est = coates_correction(h, opts.pulses).mean(axis=0)
    assert est[20] == pytest.approx(1.0, rel=0.05)
    assert est[30] == pytest.approx(0.02, rel=0.25)


def test_finite_dead_time_blinds_the_following_bins():
    lam = np.full((2000, BINS.count), 0.0)
    lam[:, 10] = 50.0  # surely detected
    lam[:, 11:14] = 5.0
    dead = 2.5 * BINS.bin_s
    opts = DetectorOptions(pulses=1, dead_time_s=dead)
    h = photon_counts_dead_time(lam, BINS, options=opts, rng=4)
    # continuous time: 50 photons per bin arrive in the first 1/50 of bin 10, so the SPAD is
    # blind until 12.5 + 0.02 bins: bin 11 blind, bin 12 re-armed for its second half
    # (1 - exp(-5 x 0.48) = 0.91 detect), then blind again through bin 13 after a detection
    # there (bins rounded to whole bins made all of 11-13 blind)
    assert h[:, 10].mean() > 0.99
    assert h[:, 11].sum() == 0 and not (h[:, 12] & h[:, 13]).any()
    assert h[:, 12].mean() == pytest.approx(1 - np.exp(-5 * 0.48), abs=0.02)
    with pytest.raises(ValueError, match="bin width"):
        photon_counts(lam, options=opts, rng=0)


def test_bad_options_are_rejected():
    with pytest.raises(ValueError, match="pulses"):
        DetectorOptions(pulses=0)
    with pytest.raises(ValueError, match="signal_photons"):
        DetectorOptions(signal_photons=-1.0)


def test_coates_correction_of_a_saturated_histogram_by_hand():
    """10 pulses: bin 0 fires 2 times (2 of 10 armed: -ln 0.8), bin 1 fires on all 8 pulses
    still armed (saturated: inf), bin 2 has no armed pulse left (0, not NaN)."""
    est = coates_correction(np.array([2, 8, 0]), 10)
    np.testing.assert_allclose(est[0], -np.log(0.8), rtol=1e-12)
    assert est[1] == np.inf and est[2] == 0.0
    # an unsaturated histogram: bin 1 has 8 armed pulses and fires on 4 of them
    np.testing.assert_allclose(
        coates_correction(np.array([[2, 4, 1]]), 10)[0],
        [-np.log(1 - 2 / 10), -np.log(1 - 4 / 8), -np.log(1 - 1 / 4)],
        rtol=1e-12,
    )


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"background_photons_per_s": -1.0}, "background_photons_per_s"),
        ({"dark_count_rate_hz": float("nan")}, "dark_count_rate_hz"),
        ({"signal_photons": float("inf")}, "signal_photons"),
        ({"dead_time_s": -1e-9}, "dead_time_s"),
        ({"dead_time_s": float("nan")}, "dead_time_s"),
    ],
)
def test_detector_options_refuse_bad_values(kw, match):
    with pytest.raises(ValueError, match=match):
        DetectorOptions(**kw)


def test_an_apd_with_a_dead_time_is_refused():
    from simlunar.lidar.apd import ApdOptions

    with pytest.raises(ValueError, match="linear-mode APD has no dead time"):
        DetectorOptions(apd=ApdOptions(), dead_time_s=1e-9)
    assert DetectorOptions(apd=ApdOptions()).regime == "linear_apd"


@pytest.mark.parametrize("dead", [0.0, np.inf])
def test_dead_time_counts_without_a_finite_dead_time_are_the_plain_counts(dead):
    """No dead time (Poisson) and an infinite one (one detection per pulse) need no bin
    width: photon_counts_dead_time hands them to photon_counts, the same draws per seed."""
    lam = np.full((3, BINS.count), 0.05)
    lam[:, 12] = 2.0
    opts = DetectorOptions(pulses=50, dead_time_s=dead)
    a = photon_counts_dead_time(lam, BINS, options=opts, rng=11)
    np.testing.assert_array_equal(a, photon_counts(lam, options=opts, rng=11))
    if np.isinf(dead):
        assert (a.sum(axis=1) <= 50).all()
