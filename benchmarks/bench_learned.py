"""Learned importance map benchmark: one map of a full-resolution guide.

``learned_map``: :meth:`simlunar.features.learned.LearnedMap.predict` of a 971 x 1674 guide (the
full moonyard's; 1.6 M rows of 42 features) with a model of 200 boosting rounds, trained here
in seconds on small synthetic pairs (the shipped experiments' models have as many rounds).
Ours: the rows split over this process's cores in Python threads
(:func:`simlunar.features.learned.predict_rows`). Reference: the same model predicting every
row in one call on one thread, as before. The two maps are equal to the bit (asserted).
``features_s`` is the feature stack alone, which both include. In a
``table2_moonyard_learned`` unit the learned maps (22 of them: two models x 11 densities) were
63 % of the time (808 of 1298 s, cProfile, one unit with ``--workers 1``).
"""

from __future__ import annotations

import time

import numpy as np


def _model(smoke: bool):
    from simlunar.features.learned import LearnedOptions
    from simlunar.planner.learning import train_learned_map
    from simlunar.reconstruction.synthetic import lit_terrain

    pairs = []
    for seed in range(2 if smoke else 4):
        t = lit_terrain((64, 96) if smoke else (128, 192), rng=seed)
        pairs.append((t.image, t.heights))
    opts = LearnedOptions(pixels_per_example=2000, max_iter=10 if smoke else 200)
    return train_learned_map(pairs, densities=[1 / 64], options=opts, rng=0)


def learned_map(*, smoke: bool = False) -> dict:
    """One-call vs chunked prediction of a learned map (``smoke``: 100 x 160 guide, 10 trees)."""
    from simlunar.features import learned as learned_mod
    from simlunar.features._stack import image_features
    from simlunar.features.learned import pitch_of
    from simlunar.reconstruction.synthetic import lit_terrain

    shape = (100, 160) if smoke else (971, 1674)
    model = _model(smoke)
    image = lit_terrain(shape, rng=7).image
    density = 1 / 512
    t0 = time.perf_counter()
    image_features(image, pitch=pitch_of(density))
    features_s = time.perf_counter() - t0
    saved = learned_mod.PREDICT_CHUNK_ROWS
    try:
        if smoke:  # exercise the chunked path at the tiny size
            learned_mod.PREDICT_CHUNK_ROWS = 1000
        t0 = time.perf_counter()
        ours = model.predict(image, density=density)
        ours_s = time.perf_counter() - t0
        learned_mod.PREDICT_CHUNK_ROWS = 10**12  # one call
        t0 = time.perf_counter()
        ref = model.predict(image, density=density)
        ref_s = time.perf_counter() - t0
    finally:
        learned_mod.PREDICT_CHUNK_ROWS = saved
    assert np.array_equal(ours, ref)
    return {
        "reference_s": round(ref_s, 3),
        "ours_s": round(ours_s, 3),
        "features_s": round(features_s, 3),
        "cores": learned_mod.predict_cores(),
        "rows": int(image.size),
        "smoke": smoke,
    }


BENCHMARKS = {"learned_map": learned_map}
