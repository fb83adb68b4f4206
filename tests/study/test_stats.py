"""Bootstrap score intervals and samples saved at equal error: hand cases, coverage, power laws."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics import score
from simlunar.study.stats import (
    FEWER,
    INTERPOLATED,
    MORE,
    best_separation,
    bootstrap_scores,
    resample_weights,
    samples_at_equal_error,
    samples_saved,
)


# --------------------------------------------------------------------------- bootstrap
def test_resample_weights_counts():
    w = resample_weights(4, 3, 500, rng=0)
    assert w.shape == (500, 4, 3)
    assert np.all(w.sum(axis=(1, 2)) == 12)
    # a seed is drawn whole: all its trials the same number of times
    assert np.all(w == w[:, :, :1])
    assert abs(w.mean() - 1.0) < 0.05  # every seed equally likely
    one = resample_weights(1, 5, 500, rng=0)  # one seed: the trials are resampled
    assert np.all(one.sum(axis=(1, 2)) == 5) and np.any(one != 1)


def test_bootstrap_hand_case_one_density_two_trials():
    # random errors 1 and 3 on trials 0 and 1, the strategy 1 and 1: a resample draws the
    # trials (0,0), (0,1)/(1,0) or (1,1) with probability 1/4, 1/2, 1/4, so the score
    # (mean random error / 1) is 1, 2 or 3 with those probabilities
    errs = {"random": [[1.0, 3.0]], "s": [[1.0, 1.0]]}
    res = bootstrap_scores(errs, [0.5], n_boot=4000, small_sample=False, rng=1)
    assert res.interval("s")[0] == pytest.approx(2.0)
    reps = res.replicates[:, 1]
    assert set(np.unique(reps)) <= {1.0, 2.0, 3.0}
    frac = [np.mean(reps == v) for v in (1.0, 2.0, 3.0)]
    assert frac == pytest.approx([0.25, 0.5, 0.25], abs=0.03)
    assert (res.low[1], res.high[1]) == (1.0, 3.0)
    assert res.interval("random") == (1.0, 1.0, 1.0)


def test_bootstrap_is_paired():
    # the strategy's error is half random's on every (seed, trial): every paired resample
    # gives exactly 2; an unpaired one would spread
    rng = np.random.default_rng(3)
    rand = rng.lognormal(0, 1, size=(4, 3, 6))
    res = bootstrap_scores({"random": rand, "half": rand / 2}, [0.5, 0.1, 0.01], rng=2)
    assert np.allclose(res.replicates[:, 1], 2.0)
    assert res.low[1] == pytest.approx(2.0) and res.high[1] == pytest.approx(2.0)


def test_point_score_with_one_seed_is_eq_4_3():
    rng = np.random.default_rng(5)
    errs = {s: rng.lognormal(0, 0.5, size=(5, 7)) for s in ("random", "a", "b")}
    dens = [1 / 2, 1 / 8, 1 / 32, 1 / 128, 1 / 512]
    res = bootstrap_scores(errs, dens, rng=0)
    ref = score(errs, dens)
    assert res.score == pytest.approx([ref[s] for s in res.strategies])


def test_bootstrap_deterministic_and_errors():
    errs = {"random": np.ones((2, 3, 4)), "a": np.full((2, 3, 4), 0.5)}
    a = bootstrap_scores(errs, [0.5, 0.25, 0.125], rng=7)
    b = bootstrap_scores(errs, [0.5, 0.25, 0.125], rng=7)
    assert np.array_equal(a.replicates, b.replicates)
    with pytest.raises(ValueError, match="reference"):
        bootstrap_scores({"a": np.ones((3, 4))}, [0.5, 0.25, 0.125], rng=0)
    with pytest.raises(ValueError, match="same"):
        bootstrap_scores({"random": np.ones((3, 4)), "a": np.ones((3, 5))}, [0.5, 0.2, 0.1], rng=0)
    with pytest.raises(ValueError, match="shape"):
        bootstrap_scores({"random": np.ones((2, 4))}, [0.5, 0.2, 0.1], rng=0)


def _synthetic(rng, n_seeds, n_trials, mu):
    """Errors (seeds, densities, trials) = mu(d) * terrain(seed, d) * own(seed, d) * noise.

    ``terrain`` is shared by the strategies (the same terrains), ``own`` is each strategy's
    response to a terrain (what makes scores vary from terrain to terrain), ``noise`` per
    trial. All effects have median 1 and the same distribution for every strategy.
    """
    d = mu["random"].size
    terrain = rng.lognormal(0.0, 0.5, size=(n_seeds, d, 1))
    return {
        s: m[None, :, None]
        * terrain
        * rng.lognormal(0.0, 0.3, size=(n_seeds, d, 1))
        * rng.lognormal(0.0, 0.3, size=(n_seeds, d, n_trials))
        for s, m in mu.items()
    }


@pytest.mark.parametrize("n_seeds", [5, 16])
def test_bootstrap_coverage_on_known_truth(n_seeds):
    # equal effect distributions: the true score is sum_d w_d mu_random(d) / mu_s(d) / sum w.
    # A seed-blind bootstrap (all pairs as independent trials of one terrain) covers far less,
    # because each terrain moves the score; so does the plain percentile interval of 5 seeds.
    dens = np.array([1 / 4, 1 / 16, 1 / 64])
    mu = {"random": np.array([1.0, 3.0, 9.0]), "s": np.array([0.8, 2.0, 5.0])}
    w = 1 / dens
    truth = float(np.sum(w * mu["random"] / mu["s"]) / w.sum())
    rng = np.random.default_rng(11)
    reps, hits, hits_blind, hits_plain = 300, 0, 0, 0
    for _ in range(reps):
        errs = _synthetic(rng, n_seeds, 6, mu)
        res = bootstrap_scores(errs, dens, n_boot=300, rng=rng)
        hits += res.low[1] <= truth <= res.high[1]
        plain = bootstrap_scores(errs, dens, n_boot=300, small_sample=False, rng=rng)
        hits_plain += plain.low[1] <= truth <= plain.high[1]
        pooled = {s: e.transpose(1, 0, 2).reshape(3, -1) for s, e in errs.items()}
        blind = bootstrap_scores(pooled, dens, n_boot=300, small_sample=False, rng=rng)
        hits_blind += blind.low[1] <= truth <= blind.high[1]
    coverage = hits / reps
    assert 0.9 <= coverage <= 0.99, coverage
    assert hits_blind / reps < coverage - 0.15, (hits_blind / reps, coverage)
    if n_seeds == 5:
        assert hits_plain / reps < 0.88, hits_plain / reps


def test_best_separation():
    rng = np.random.default_rng(0)
    base = rng.lognormal(0, 0.3, size=(6, 2, 10))
    errs = {"random": base, "good": base / 2, "close": base / 1.98, "bad": base * 2}
    res = bootstrap_scores(errs, [0.5, 0.05], rng=1)
    sep = best_separation(res)
    assert (sep.best, sep.runner_up) == ("good", "close")
    assert sep.significant  # paired, both exact multiples: the difference has no spread
    # "a" is as good as "b" on average but varies a lot from terrain to terrain
    noise = rng.lognormal(0, 0.5, size=(6, 2, 1))
    noisy = {"random": base, "a": base / 1.5 * noise / noise.mean(), "b": base / 1.5}
    sep = best_separation(bootstrap_scores(noisy, [0.5, 0.05], rng=1), among=["a", "b"])
    assert not sep.significant and sep.low < 0 < sep.high
    assert best_separation(res, among=["good"]) is None


# --------------------------------------------------------------------------- samples saved
def test_equal_error_power_law_exact():
    # e = 4 k^-0.5: the error e is reached at k = (4 / e)^2, exactly, inside the range
    ks = np.array([10.0, 40.0, 160.0, 640.0])
    e = 4 * ks**-0.5
    targets = 4 * np.array([20.0, 100.0, 333.0]) ** -0.5
    k, flag = samples_at_equal_error(ks, e, targets)
    assert k == pytest.approx([20.0, 100.0, 333.0])
    assert np.all(flag == INTERPOLATED)


def test_equal_error_extrapolation_flagged_and_clipped():
    ks = np.array([10.0, 40.0, 160.0])
    e = 4 * ks**-0.5
    k, flag = samples_at_equal_error(ks, e, [4 * 5.0**-0.5, 4 * 1000.0**-0.5, 1e-6], k_max=500)
    assert k[0] == pytest.approx(5.0) and flag[0] == FEWER  # end segment's power law
    assert k[1] == 500 and flag[1] == MORE  # 1000 clipped to k_max
    assert k[2] == 500 and flag[2] == MORE


def test_equal_error_monotone_envelope():
    # an uptick at k = 40 is ignored: error 1.0 is first reached at k = 20 (log-log midway
    # between 10 (e 2) and 40 (e 0.5) is the envelope 10 -> 20 -> ...)
    ks = [10.0, 20.0, 40.0, 80.0]
    e = [2.0, 1.0, 1.5, 0.5]
    k, flag = samples_at_equal_error(ks, e, [1.0, 0.75])
    assert k[0] == pytest.approx(20.0)
    # between 20 (1.0, also the envelope at 40) and 80 (0.5): log-linear
    assert k[1] == pytest.approx(40 * 2 ** (np.log(0.75) / np.log(0.5)))
    assert np.all(flag == 0)


def test_samples_saved_analytic_factor():
    # random e = k^-1, strategy e = (2k)^-1 (as good as random with twice the samples):
    # factor 2 at every density whose target lies in random's range
    ks = np.array([8.0, 16.0, 32.0, 64.0, 128.0])
    res = samples_saved({"random": 1 / ks, "s": 1 / (2 * ks)}, ks, n_pixels=1000)
    assert res.factor["random"] == pytest.approx(np.ones(5))
    assert res.factor["s"][:4] == pytest.approx(2.0)
    assert list(res.flag["s"]) == [0, 0, 0, 0, MORE]
    assert res.factor["s"][4] == pytest.approx(2.0)  # the power law extended exactly
    assert res.summary["s"] == pytest.approx(2.0) and res.n_summary["s"] == 4
    # against a grid with e = (4k)^-1 the strategy needs twice the samples: factor 1/2
    grid = samples_saved({"grid": 1 / (4 * ks), "s": 1 / (2 * ks)}, ks, reference="grid")
    assert grid.factor["s"][1:] == pytest.approx(0.5)
    assert grid.flag["s"][0] == FEWER
    with pytest.raises(ValueError, match="reference"):
        samples_saved({"s": 1 / ks}, ks)
