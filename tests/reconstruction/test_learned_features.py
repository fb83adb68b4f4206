"""Features of the learned reconstruction (simlunar.reconstruction.learned_features)."""

from __future__ import annotations

import numpy as np

from simlunar.features._stack import FEATURE_NAMES
from simlunar.reconstruction import learned
from simlunar.reconstruction.learned_features import (
    IMAGE_SIGNED,
    SAMPLE_FEATURES,
    SHADING_FEATURE,
    anchor,
    feature_names,
    sample_scale,
)


def test_feature_names_in_column_order():
    names = feature_names()
    assert len(names) == len(FEATURE_NAMES) + len(IMAGE_SIGNED) + len(SAMPLE_FEATURES)
    assert names[: len(FEATURE_NAMES)] == tuple(f"image_{n}" for n in FEATURE_NAMES)
    assert feature_names(with_shading=True) == (*names, SHADING_FEATURE)


def test_samples_on_a_plane_have_no_height_unit():
    rng = np.random.default_rng(3)
    pts = rng.uniform(0, 20, (30, 2))
    vals = 2.0 + 0.5 * pts[:, 0] - 0.25 * pts[:, 1]
    h, loo = sample_scale(pts, vals)
    assert h == 0.0 and loo.shape == (30,)
    np.testing.assert_allclose(loo, 0.0, atol=1e-9)


def test_duplicates_are_averaged_and_a_bump_gives_a_scale():
    pts = np.array([[0, 0], [0, 10], [10, 0], [10, 10], [5, 5], [5, 5]], float)
    vals = np.array([0, 0, 0, 0, 1.0, 3.0])  # the centre twice: mean 2
    h, loo = sample_scale(pts, vals)
    assert loo.shape == (5,)  # five distinct positions
    assert h > 0 and np.isclose(h, np.sqrt(np.mean(loo**2)))


def test_anchor_keeps_the_measured_cells():
    rng = np.random.default_rng(0)
    z_lin = rng.normal(size=(12, 12))
    residual = rng.normal(size=(12, 12))
    pts = np.array([[0, 0], [0, 11], [11, 0], [11, 11], [6, 5], [3, 8]], float)
    z = anchor(z_lin, residual, pts)
    r, c = pts.astype(int).T
    np.testing.assert_allclose(z[r, c], z_lin[r, c], atol=1e-9)
    assert not np.allclose(z, z_lin)


def test_learned_re_exports_the_features():
    assert learned.feature_names is feature_names and learned.anchor is anchor


def test_sample_distance_by_hand():
    from simlunar.reconstruction.learned_features import _sample_distance

    d = _sample_distance(np.array([[0.0, 0.0], [2.2, 3.0]]), (3, 4), pitch=2.0)
    assert d[0, 0] == 0 and d[2, 3] == 0 and d[0, 3] == 2.0 and np.isclose(d[1, 1], np.sqrt(2))
    assert d[2, 0] == 2.0  # (2, 0) is two rows from (0, 0) and three columns from (2, 3)
    outside = _sample_distance(np.array([[9.0, 9.0]]), (3, 4), pitch=2.0)
    assert (outside == 8.0).all()
