"""Nelder-Mead fit of feature-map combination coefficients."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.planner import fit_combination, plan


def _scene(seed, shape=(48, 64)):
    rng = np.random.default_rng(seed)
    rr, cc = np.mgrid[0 : shape[0], 0 : shape[1]]
    depth = np.zeros(shape)
    for _ in range(6):  # bumps on a flat plane
        r0, c0, rad = rng.uniform(0, shape[0]), rng.uniform(0, shape[1]), rng.uniform(2, 6)
        depth += rad * np.exp(-((rr - r0) ** 2 + (cc - c0) ** 2) / rad**2)
    gy, gx = np.gradient(depth)
    return depth, 1.0 / np.sqrt(1.0 + gx**2 + gy**2)  # Lambert, overhead light


def test_fit_improves_on_start_and_is_deterministic():
    scenes = [_scene(1), _scene(2)]
    kw = dict(densities=(1 / 8, 1 / 32), trials=1, maxiter=8, x0=(1.0, 0.0, 0.0))
    fit = fit_combination(scenes, rng=0, **kw)
    assert fit.score >= fit.initial_score
    assert fit.nfev > 3
    assert all(v >= 0 for v in fit.coefficients.values())
    assert sum(fit.coefficients.values()) == pytest.approx(1.0)
    again = fit_combination(scenes, rng=0, **kw)
    assert again.coefficients == fit.coefficients
    # the fitted coefficients plug into the combination strategy
    p = plan("combination", 50, image=scenes[0][1], rng=0, coefficients=fit.coefficients)
    assert p.k == 50


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"features": ("sobel",)}, "unknown feature"),
        ({"densities": (0.0,)}, "densities"),
        ({"x0": (1.0,)}, "x0 must have 3"),
    ],
)
def test_fit_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        fit_combination([_scene(1)], rng=0, trials=1, maxiter=1, **kwargs)


def test_fit_rejects_mismatched_scene():
    depth, image = _scene(1)
    with pytest.raises(ValueError, match="scene 0"):
        fit_combination([(depth[:10], image)], rng=0)
