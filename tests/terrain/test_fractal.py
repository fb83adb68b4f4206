"""fBm spectral slope, RMS, periodicity; undulating bed."""

import numpy as np
import pytest

from simlunar.terrain.fractal import fbm, radial_power_spectrum, undulating_bed


@pytest.mark.parametrize("hurst", [0.3, 0.8])
def test_radial_power_spectrum_slope_is_minus_2h_plus_2(hurst):
    z = fbm((512, 512), spacing=0.5, hurst=hurst, rms=1.0, periodic=True, rng=11)
    k, p = radial_power_spectrum(z, 0.5, nbins=30)
    # fit over the middle decade (away from the lowest, sparsely sampled annuli and Nyquist)
    sel = (k > 8 / (0.5 * 512)) & (k < 0.25 / 0.5)
    slope = np.polyfit(np.log(k[sel]), np.log(p[sel]), 1)[0]
    assert slope == pytest.approx(-(2 * hurst + 2), abs=0.1)


def test_rms_and_zero_mean_and_determinism():
    a = fbm((100, 150), spacing=0.2, hurst=0.6, rms=0.3, periodic=False, rng=2)
    b = fbm((100, 150), spacing=0.2, hurst=0.6, rms=0.3, periodic=False, rng=2)
    c = fbm((100, 150), spacing=0.2, hurst=0.6, rms=0.3, periodic=False, rng=3)
    assert a.std() == pytest.approx(0.3) and abs(a.mean()) < 1e-12
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert np.isfinite(a).all()


def test_periodic_surface_wraps_and_cropped_one_does_not():
    per = fbm((128, 128), spacing=1.0, hurst=0.8, rms=1.0, periodic=True, rng=4)
    non = fbm((128, 128), spacing=1.0, hurst=0.8, rms=1.0, periodic=False, rng=4)
    # the jump across the wrap edge is as small as an interior step for the periodic surface
    interior = np.abs(np.diff(per, axis=1)).mean()
    assert np.abs(per[:, 0] - per[:, -1]).mean() < 1.5 * interior
    assert np.abs(non[:, 0] - non[:, -1]).mean() > 3 * np.abs(np.diff(non, axis=1)).mean()


def test_rolloff_flattens_the_long_wavelengths():
    z = fbm((512, 512), spacing=1.0, hurst=0.8, rms=1.0, periodic=True, rolloff_m=16.0, rng=5)
    k, p = radial_power_spectrum(z, 1.0, nbins=30)
    low = k < 1 / 32.0
    assert abs(np.polyfit(np.log(k[low]), np.log(p[low]), 1)[0]) < 0.6  # flat, not -3.6


def test_undulating_bed_has_requested_rms_and_gaussian_spectrum_slope_rms():
    # power ~ exp(-k^2 / sk^2) in 2-D has <k^2> = sk^2, so the RMS gradient magnitude is
    # 2 pi * amplitude * sk with sk = 1 / wavelength: 2 pi * 0.02 * 2 = 0.2513
    bed = undulating_bed((400, 600), spacing=0.01, amplitude=0.02, wavelength=0.5, rng=1)
    assert bed.std() == pytest.approx(0.02)
    gy, gx = np.gradient(bed, 0.01)
    # a 4 m x 6 m patch holds only ~100 bed wavelengths^2: 10 % sampling margin
    assert np.sqrt((gx**2 + gy**2).mean()) == pytest.approx(2 * np.pi * 0.02 * 2.0, rel=0.1)


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"hurst": 0.0}, "hurst"),
        ({"hurst": 1.0}, "hurst"),
        ({"spacing": -1.0}, "spacing"),
        ({"rms": -1.0}, "rms"),
        ({"rolloff_m": 0.0}, "rolloff"),
    ],
)
def test_bad_parameters_name_the_field(kw, field):
    args = {"spacing": 1.0, "hurst": 0.5, "rms": 1.0} | kw
    with pytest.raises(ValueError, match=field):
        fbm((32, 32), rng=0, **args)
