"""Photon-level facts of the LIDAR receiver, each from a closed form: a photon's energy at the
laser's wavelength, no counts where no light falls on a default detector, and the detection
probability of a pulse narrower than a bin without background."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar.detector import DetectorOptions, expected_counts
from simlunar.lidar.hardware import LidarHardware
from simlunar.lidar.ranging import detection_probability
from simlunar.lidar.waveform import PulseOptions, TimeBins


def test_a_1064_nm_photon_carries_h_c_over_lambda():
    # h = 6.62607015e-34 J s and c = 299792458 m/s exactly (SI 2019): h c = 1.98644586e-25 J m,
    # / 1064 nm = 1.86696e-19 J (1.165 eV)
    hw = LidarHardware(wavelength_m=1064e-9)
    assert hw.photon_energy_j == pytest.approx(1.98644586e-25 / 1064e-9, rel=1e-8)
    assert hw.photon_energy_j / 1.602176634e-19 == pytest.approx(1.16527, rel=1e-5)


def test_a_default_detector_counts_nothing_where_no_light_falls():
    """No signal, no sun: a detector with its default options (no dark counts) expects exactly
    zero photons in every bin; 100 dark counts per second add 100 x the bin's duration."""
    bins = TimeBins(0.0, 0.3, 8)
    dark = expected_counts(np.zeros(8), 0.0, bins, DetectorOptions())
    np.testing.assert_array_equal(dark, np.zeros(8))
    noisy = expected_counts(np.zeros(8), 0.0, bins, DetectorOptions(dark_count_rate_hz=100.0))
    np.testing.assert_allclose(noisy, 100.0 * bins.bin_s, rtol=1e-12)


def test_a_pulse_narrower_than_a_bin_is_detected_as_its_poisson_law_says():
    """A 0.5 ns FWHM pulse on 0.3 m bins (1 ns): sigma = 0.21 bin, so the 3-bin test window
    (m = 1) holds the whole pulse wherever the return falls in its central bin (>= 4.7
    sigma on each side). Without background the threshold is 0 photons and the return is
    detected when at least one photon arrives: P = 1 - exp(-n S) = 1 - exp(-3) for 3 pulses of
    1 photon (n S = 3 reaches min_photons = 3); 1 pulse (n S = 1 < 3) is never a return."""
    bins, pulse = TimeBins(0.0, 0.3, 100), PulseOptions(fwhm_s=0.5e-9)
    assert pulse.sigma_bins(bins) == pytest.approx(0.2122, abs=1e-4)
    p = detection_probability([1.0, 1.0, 2.0], 0.0, [3, 1, 3], bins=bins, pulse=pulse)
    np.testing.assert_allclose(p, [1 - np.exp(-3.0), 0.0, 1 - np.exp(-6.0)], rtol=1e-6)
