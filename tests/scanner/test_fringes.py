"""Fringe phase math: period hand cases, wrapped phase and modulation, phase noise against the
closed form, unwrapping hand case."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import fringes as fr


def test_fringe_periods_hand_cases():
    assert fr.fringe_periods(128, 8, 8) == (512.0, 64.0, 8.0)
    assert fr.fringe_periods(50, 8, 8) == (64.0, 8.0)  # 64 >= 1.1 * 50
    assert fr.fringe_periods(60, 8, 8) == (512.0, 64.0, 8.0)  # 64 < 66: one more level
    assert fr.fringe_periods(10, 16, 4) == (16.0,)  # one fringe holds the axis
    with pytest.raises(ValueError, match="ratio > 1"):
        fr.fringe_periods(100, 8, 1.0)


def test_wrapped_phase_and_modulation_of_a_hand_case():
    # N = 4: I_n = A + B cos(phi + n pi / 2) -> S = sum I_n sin = -2 B sin phi, C = 2 B cos phi
    A, B, phi = 0.3, 0.2, 1.0
    frames = np.array([A + B * np.cos(phi + n * np.pi / 2) for n in range(4)])
    got_phi, got_b, got_a = fr.wrapped_phase(frames)
    assert got_phi == pytest.approx(phi) and got_b == pytest.approx(B) and got_a == pytest.approx(A)
    # a wrapped phase is in [0, 2 pi)
    neg = np.array([A + B * np.cos(-1.0 + n * np.pi / 2) for n in range(4)])
    assert fr.wrapped_phase(neg)[0] == pytest.approx(2 * np.pi - 1.0)
    with pytest.raises(ValueError, match="at least 3 frames"):
        fr.wrapped_phase(frames[:2])


@pytest.mark.parametrize("steps", [3, 4, 7])
def test_phase_noise_matches_the_closed_form(steps):
    # sigma_phi = sqrt(2 / N) sigma_I / B (REFERENCES, phase shift); 40 000 pixels: the sample
    # standard deviation has a relative standard error of 1 / sqrt(2 n) = 0.35 %
    rng = np.random.default_rng(steps)
    n, A, B, sigma = 40_000, 0.4, 0.25, 0.004
    phi = rng.uniform(0, 2 * np.pi, n)
    d = 2 * np.pi * np.arange(steps) / steps
    clean = A + B * np.cos(phi[None] + d[:, None])
    got, mod, _ = fr.wrapped_phase(clean + rng.normal(0, sigma, clean.shape))
    err = np.angle(np.exp(1j * (got - phi)))
    want = fr.phase_noise_std(steps, sigma, B)
    assert want == pytest.approx(np.sqrt(2 / steps) * sigma / B)
    assert np.std(err) == pytest.approx(want, rel=0.02)
    assert abs(np.mean(err)) < 4 * want / np.sqrt(n)  # unbiased
    assert np.mean(mod) == pytest.approx(B, rel=0.01)


def test_unwrap_hand_case_and_disagreement():
    # periods 40 and 10: true fine phase 2 pi * 2.3 -> wrapped 0.3 * 2 pi, coarse 2 pi 2.3 / 4
    coarse, fine = 2 * np.pi * 2.3 / 4, 2 * np.pi * 0.3
    big, dis = fr.unwrap([coarse, fine], [40.0, 10.0])
    assert big == pytest.approx(2 * np.pi * 2.3) and dis == pytest.approx(0.0, abs=1e-12)
    # a coarse phase off by 0.35 rad (1.4 rad once scaled by 4): same fringe order, large
    # disagreement
    big, dis = fr.unwrap([coarse + 0.35, fine], [40.0, 10.0])
    assert big == pytest.approx(2 * np.pi * 2.3) and dis == pytest.approx(1.4)
    with pytest.raises(ValueError, match="one phase per period"):
        fr.unwrap([coarse], [40.0, 10.0])
