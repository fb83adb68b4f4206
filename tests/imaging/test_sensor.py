import numpy as np
import pytest

from simlunar.imaging.sensor import SensorModel, apply_sensor


def _dn(img, model):
    return np.round(img.astype(np.float64) * model.max_dn)


def test_photon_transfer_mean_and_variance():
    # gain 1 e-/DN: var(DN) = mean electrons (Poisson) + read^2 + 1/12 (rounding), in DN^2
    m = SensorModel(exposure=100.0, full_well_e=1e5, read_noise_e=3.0, bits=16, gain=1.0)
    out = apply_sensor(np.ones((400, 500)), m, rng=1)
    dn = _dn(out, m)
    assert dn.mean() == pytest.approx(100.0, abs=0.1)
    # 200k pixels: relative standard error of a variance estimate ~ sqrt(2/n) = 0.3 %; allow 2 %
    assert dn.var() == pytest.approx(100.0 + 9.0 + 1 / 12, rel=0.02)


def test_shot_noise_only_variance_scales_with_signal():
    m = SensorModel(exposure=1.0, full_well_e=1e6, read_noise_e=0.0, bits=20, gain=1.0)
    for mean in (20.0, 500.0):
        dn = _dn(apply_sensor(np.full((300, 300), mean), m, rng=2), m)
        assert dn.var() == pytest.approx(mean, rel=0.03)


def test_quantisation_level_count_is_2_to_bits(rng):
    m = SensorModel(exposure=1000.0, full_well_e=1000.0, read_noise_e=0.0, bits=4)
    ramp = np.linspace(0, 1.2, 100_000).reshape(100, 1000)
    out = apply_sensor(ramp, m, rng=rng)
    levels = np.unique(out)
    assert len(levels) == 2**4
    np.testing.assert_allclose(levels, np.arange(16) / 15, atol=1e-7)
    assert out.dtype == np.float32 and out.min() == 0.0 and out.max() == 1.0


def test_saturation_clips_at_full_well():
    m = SensorModel(exposure=1e4, full_well_e=5000.0, read_noise_e=0.0, bits=12)
    out = apply_sensor(np.full((50, 50), 10.0), m, rng=0)
    assert np.all(out == 1.0)
    # with read noise the saturated level still cannot exceed 1 and cannot go below black
    m2 = SensorModel(exposure=1e4, full_well_e=5000.0, read_noise_e=5.0, bits=12, black_level=64)
    out2 = apply_sensor(np.stack([np.zeros((50, 50)), np.full((50, 50), 10.0)]), m2, rng=0)
    assert out2.max() <= 1.0 and out2.min() >= 0.0
    assert _dn(out2[0], m2).mean() == pytest.approx(
        64, abs=0.3
    )  # black level in the dark (sd 4 DN / 50)


def test_determinism_and_independent_seeds(rng):
    img = rng.random((64, 64, 3))
    m = SensorModel()
    a = apply_sensor(img, m, rng=7)
    b = apply_sensor(img, m, rng=7)
    c = apply_sensor(img, m, rng=8)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a.shape == img.shape


def test_gamma_and_callable_responses():
    lin = SensorModel(exposure=1.0, full_well_e=1e6, read_noise_e=0.0, bits=16, gain=1e6 / 65535)
    gam = SensorModel(
        exposure=1.0,
        full_well_e=1e6,
        read_noise_e=0.0,
        bits=16,
        gain=1e6 / 65535,
        response="gamma",
        gamma=2.0,
    )
    x = np.full((100, 100), 250_000.0)  # a quarter of the full well: shot noise ~0.2 %
    a = apply_sensor(x, lin, rng=3)
    g = apply_sensor(x, gam, rng=3)
    assert a.mean() == pytest.approx(0.25, rel=1e-3)
    np.testing.assert_allclose(g, np.sqrt(a), rtol=1e-6)
    sq = SensorModel(
        exposure=1.0,
        full_well_e=1e6,
        read_noise_e=0.0,
        bits=16,
        gain=1e6 / 65535,
        response=lambda v: v**2,
    )
    np.testing.assert_allclose(apply_sensor(x, sq, rng=3), a.astype(np.float64) ** 2, rtol=1e-6)


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"bits": 0}, "bits"),
        ({"exposure": -1}, "exposure"),
        ({"read_noise_e": -1}, "read_noise"),
        ({"response": "log"}, "response"),
        ({"gain": 0}, "gain"),
        ({"black_level": 99999}, "black"),
    ],
)
def test_bad_parameters_name_the_field(kw, field):
    with pytest.raises(ValueError, match=field):
        SensorModel(**kw)


# --- the compiled shot-noise sampler (exact Poisson below POISSON_EXACT_BELOW, normal above) ---


def _electrons(mean, n=200_000, seed=11):
    # gain 1 e-/DN, no read noise, 24-bit ADC: the DN is the electron count (rounded)
    m = SensorModel(exposure=1.0, full_well_e=1e7, read_noise_e=0.0, bits=24, gain=1.0)
    return _dn(apply_sensor(np.full(n, mean, np.float32), m, rng=seed), m)


@pytest.mark.parametrize("mean", [0.3, 3.7, 20.0, 49.0])
def test_shot_noise_is_exactly_poisson_below_the_threshold(mean):
    from scipy import stats

    from simlunar.imaging.sensor import POISSON_EXACT_BELOW

    assert mean < POISSON_EXACT_BELOW
    k = _electrons(mean).astype(int)
    assert np.all(k == _electrons(mean))  # integer counts
    # chi-square goodness of fit against the Poisson pmf over bins with >= 20 expected counts
    ks = np.arange(0, int(mean + 8 * np.sqrt(mean) + 10))
    expected = stats.poisson.pmf(ks, mean) * k.size
    observed = np.bincount(k, minlength=ks.size)[: ks.size]
    keep = expected >= 20
    chi2 = np.sum((observed[keep] - expected[keep]) ** 2 / expected[keep])
    # p > 1e-4 for the right law; a Poisson of mean * 1.01 already fails at 20 and 49
    assert stats.chi2.sf(chi2, keep.sum() - 1) > 1e-4


@pytest.mark.parametrize("mean", [50.0, 64.0, 400.0, 12_000.0])
def test_shot_noise_above_the_threshold_has_poisson_mean_variance_and_skew(mean):
    from scipy import stats

    k = _electrons(mean)
    n = k.size
    # mean exact; variance mu + 1/18 (Cornish-Fisher term) + 1/12 (DN rounding)
    assert abs(k.mean() - mean) < 4 * np.sqrt(mean / n)
    var = mean + 1 / 18 + 1 / 12
    assert abs(k.var() - var) < 4 * var * np.sqrt(2 / n)
    # third cumulant of the Poisson law: skewness 1 / sqrt(mu) (a plain normal gives 0)
    if mean < 1000:
        assert abs(stats.skew(k) - 1 / np.sqrt(mean)) < 4 * np.sqrt(6 / n)


def test_sampler_matches_numpys_poisson_in_distribution():
    from reference_scanner import apply_sensor_reference

    m = SensorModel(exposure=30.0, full_well_e=2000.0, read_noise_e=2.0, bits=12)
    rad = np.repeat(np.array([0.0, 0.05, 0.6, 1.9, 20.0, 80.0]), 40_000).reshape(6, -1)
    ours = _dn(apply_sensor(rad, m, rng=5), m)
    ref = _dn(apply_sensor_reference(rad, m, rng=5), m)
    for a, b in zip(ours, ref):
        se = np.sqrt((a.var() + b.var()) / a.size) + 1e-9
        assert abs(a.mean() - b.mean()) < 5 * se
        assert a.var() == pytest.approx(b.var(), rel=0.05, abs=0.02)


def test_nan_inf_and_negative_radiance_count_as_dark_and_float32_equals_float64():
    m = SensorModel(exposure=1e3, read_noise_e=0.0, bits=12)
    x = np.array([[np.nan, np.inf, -np.inf, -3.0, 0.0]])
    assert np.all(apply_sensor(x, m, rng=0) == 0.0)
    y = np.random.default_rng(1).random((40, 50)).astype(np.float32)
    np.testing.assert_array_equal(
        apply_sensor(y, m, rng=4), apply_sensor(y.astype(np.float64), m, rng=4)
    )
