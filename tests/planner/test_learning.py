"""Training the learned map: the error target (log squared error of uniform layouts) where
the terrain is rough, seeded; the training inputs' checks."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.features.learned import pitch_of
from simlunar.planner.learning import error_target, train_learned_map


def _pair(shape=(24, 24)):
    r = np.random.default_rng(0)
    return np.clip(0.5 + 0.1 * r.standard_normal(shape), 0.01, None), r.standard_normal(shape)


def test_error_target_lies_on_the_rough_patch():
    z = np.zeros((64, 64))
    z[20:40, 20:40] = np.random.default_rng(2).standard_normal((20, 20))
    t = error_target(z, density=1 / 16, rng=0)
    assert t.shape == z.shape and t.dtype == np.float32
    assert t[25:35, 25:35].mean() > t[:10, :10].mean() + 5  # log units: e^5 ~ 150x


def test_training_inputs_are_validated():
    img, z = _pair()
    with pytest.raises(ValueError, match="truth"):
        train_learned_map([(img, z[:, :10])], densities=[0.1], rng=0)
    with pytest.raises(ValueError, match="distinct"):
        train_learned_map([(img, z)], densities=[0.1, 0.1], rng=0)
    with pytest.raises(ValueError, match="density"):
        pitch_of(0.0)
    with pytest.raises(ValueError, match="at least one"):
        train_learned_map([], densities=[0.1], rng=0)


def test_error_target_is_seeded():
    z = np.random.default_rng(5).standard_normal((32, 32))
    a = error_target(z, density=1 / 8, rng=3)
    np.testing.assert_array_equal(a, error_target(z, density=1 / 8, rng=3))
    assert not np.array_equal(a, error_target(z, density=1 / 8, rng=4))
    # more layouts average more: the target still lies where it did
    b = error_target(z, density=1 / 8, layouts=6, rng=3)
    assert np.corrcoef(a.ravel(), b.ravel())[0, 1] > 0.5


def test_error_target_refuses_bad_truth():
    with pytest.raises(
        ValueError, match=r"^truth must be a finite \(rows, cols\) array, got shape \(4,\)$"
    ):
        error_target(np.zeros(4), density=0.5)
    z = np.zeros((8, 8))
    z[3, 3] = np.nan
    with pytest.raises(ValueError, match=r"got shape \(8, 8\)$"):
        error_target(z, density=0.5)


def _lit(seed):
    from simlunar.reconstruction.synthetic import lit_terrain

    t = lit_terrain((96, 128), rng=seed)  # constant albedo: shading explains the image
    return t.image, t.heights, t.light


def _shading_fn(image, truth, light):
    from simlunar.reconstruction import Guide, run_reconstruction

    g = Guide(image, light=light)
    return lambda rc, v: run_reconstruction("shading", rc, v, truth.shape, guide=g).heights


def test_error_target_is_the_error_of_the_reconstruction_given():
    z = np.random.default_rng(5).standard_normal((32, 32))
    # a reconstruction that is exact: no error anywhere, the target is the floor log(1e-30)
    exact = error_target(z, density=1 / 8, rng=3, reconstruct=lambda rc, v: z)
    np.testing.assert_allclose(exact, np.log(np.float32(1e-30)), rtol=1e-6)
    # linear passed explicitly is the default, exactly
    from simlunar.reconstruction import reconstruct

    lin = error_target(
        z, density=1 / 8, rng=3, reconstruct=lambda rc, v: reconstruct(rc, v, z.shape)
    )
    np.testing.assert_array_equal(lin, error_target(z, density=1 / 8, rng=3))


def test_the_fused_target_differs_from_linears_where_shading_explains_the_image():
    # synthetic Lambert terrain, constant albedo, 30 deg sun, 96 x 128 cells. Measured on
    # seeds 0-2 at 1/32 and 1/64: shading's smoothed squared error is e^0.89-e^1.12 times
    # smaller than linear's on average, and lies elsewhere (correlation of the log targets
    # 0.72-0.78)
    for seed in range(3):
        image, z, light = _lit(seed)
        for d in (1 / 32, 1 / 64):
            a = error_target(z, density=d, rng=0)
            b = error_target(z, density=d, rng=0, reconstruct=_shading_fn(image, z, light))
            assert a.mean() - b.mean() > 0.6, (seed, d)
            assert np.corrcoef(a.ravel(), b.ravel())[0, 1] < 0.9, (seed, d)


def test_a_map_trained_on_the_fused_error_records_it_and_predicts_otherwise():
    from simlunar.features.learned import LearnedOptions
    from simlunar.reconstruction import Guide

    lits = [_lit(s) for s in range(3)]
    ex = [(img, z) for img, z, _ in lits]
    fast = LearnedOptions(layouts=1, pixels_per_example=2000, max_iter=20)
    plain = train_learned_map(ex, densities=[1 / 32], options=fast, rng=0)
    same = train_learned_map(ex, densities=[1 / 32], options=fast, rng=0,
                             error_reconstruction="linear")  # fmt: skip
    guides = [Guide(img, light=s) for img, _, s in lits]
    fused = train_learned_map(ex, densities=[1 / 32], options=fast, rng=0,
                              error_reconstruction="shading", guides=guides)  # fmt: skip
    # linear: the record and the model of before (no new key)
    assert "error_reconstruction" not in plain.meta and set(same.meta) == set(plain.meta)
    img = ex[0][0]
    p0 = plain.predict_log(img, density=1 / 32)
    np.testing.assert_array_equal(p0, same.predict_log(img, density=1 / 32))
    assert fused.meta["error_reconstruction"] == "shading"
    assert fused.meta["error_guide_frames"] == ["sun"]
    assert fused.meta["error_reconstruction_options"]["heldout_check"] is True
    # measured correlation of the two maps' log predictions on a training image: 0.73
    p1 = fused.predict_log(img, density=1 / 32)
    assert np.corrcoef(p0.ravel(), p1.ravel())[0, 1] < 0.9


def test_error_reconstruction_inputs_are_checked():
    from simlunar.reconstruction import Guide

    img, z = _pair()
    with pytest.raises(ValueError, match="unknown reconstruction 'shadin'"):
        train_learned_map([(img, z)], densities=[0.1], rng=0, error_reconstruction="shadin")
    with pytest.raises(ValueError, match="one per example"):
        train_learned_map([(img, z)], densities=[0.1], rng=0, error_reconstruction="shading",
                          guides=[])  # fmt: skip
    with pytest.raises(ValueError, match=r"guides\[0\]"):
        train_learned_map([(img, z)], densities=[0.1], rng=0, error_reconstruction="shading",
                          guides=[Guide(np.ones((5, 5)))])  # fmt: skip
