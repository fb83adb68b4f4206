"""The map registry: name -> (map function, options class); feature_map checks options by the
entry's class and names the valid ones."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.features import MAPS, WaveletOptions, feature_map, image_maps, map_options, wavelet


def test_entries_carry_their_options():
    assert MAPS["wavelet"].options is WaveletOptions
    assert map_options("wavelet") == ("wavelet", "levels", "boundary")
    assert map_options("gradient") == ()
    assert "learned" not in image_maps() and MAPS["learned"].meta["needs_model"]


def test_feature_map_runs_the_entry_with_checked_options():
    img = np.random.default_rng(1).random((16, 24))
    np.testing.assert_array_equal(feature_map("wavelet", img, levels=2), wavelet(img, levels=2))
    with pytest.raises(ValueError, match=r"unknown option 'levls'.*did you mean 'levels'"):
        feature_map("wavelet", img, levls=2)
    with pytest.raises(ValueError, match="levels must be >= 1"):
        feature_map("wavelet", img, levels=0)
    with pytest.raises(ValueError, match=r"needs option\(s\) \['density', 'model'\]"):
        feature_map("learned", img)
    with pytest.raises(ValueError, match=r"unknown feature 'wavlet'.*did you mean 'wavelet'"):
        feature_map("wavlet", img)
