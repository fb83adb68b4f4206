"""A unit's study meta (simlunar/pipeline/study_meta.py): plain scores and means over trials."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from simlunar.pipeline.study_meta import plain_scores, rounds_meta, trial_means


def test_trial_means_of_reconstruction_info_skip_missing_values():
    v = np.array([[0.2, 0.4], [np.nan, 0.3], [np.nan, np.nan]])
    assert trial_means(v) == [pytest.approx(0.3), pytest.approx(0.3), None]


def test_plain_scores_are_plain_floats_by_name():
    got = plain_scores({"rmse": {"grid": np.float32(0.5)}})
    assert got == {"rmse": {"grid": 0.5}} and type(got["rmse"]["grid"]) is float


def test_rounds_meta_is_empty_for_one_shot_studies():
    assert rounds_meta(SimpleNamespace(rounds={})) == {}
    study = SimpleNamespace(rounds={"seq": np.array([[2.0, 4.0], [3.0, 3.0]])})
    assert rounds_meta(study) == {"rounds": {"seq": [3.0, 3.0]}}
