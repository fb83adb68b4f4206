"""Training the learned importance map (the paper's "learn a mapping", section 3.1): the
target is where a uniform layout's reconstruction error lies; the model
(:class:`simlunar.features.learned.LearnedMap`) then predicts it from the guide image alone.

Training lives in ``planner/`` because its target is made with a layout and a reconstruction;
the prediction (``features.learned``) needs only the image.
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from dataclasses import asdict

import numpy as np
from scipy import ndimage
from sklearn.ensemble import HistGradientBoostingRegressor
from threadpoolctl import threadpool_limits

from simlunar.features._stack import FEATURE_NAMES, FEATURE_SET_VERSION, image_features
from simlunar.features.learned import (
    FORMAT,
    LearnedMap,
    LearnedOptions,
    _sha256_array,
    _versions,
    pitch_of,
)
from simlunar.features.maps import check_image
from simlunar.planner.sequential import uniform_layout
from simlunar.reconstruction import reconstruct

__all__ = ["error_target", "train_learned_map"]


def error_target(truth, *, density: float, layouts: int = 3, rng=None) -> np.ndarray:
    """Log squared error of uniform layouts' reconstructions, smoothed at half the pitch.

    Parameters
    ----------
    truth : ndarray, shape (rows, cols)
        True depth (m), finite.
    density : float in (0, 1]
        Sample fraction k / N of the layouts.
    layouts : int
        Independent uniform layouts (:func:`simlunar.planner.sequential.uniform_layout`)
        whose squared errors are averaged.
    rng : None, int, SeedSequence or Generator

    Returns
    -------
    ndarray of float32, shape (rows, cols)
        log(G_{pitch/2} * mean_layouts (recon - truth)^2 + eps), eps = 1e-6 x its mean.
    """
    rng = np.random.default_rng(rng)
    z = np.asarray(truth, dtype=np.float64)
    if z.ndim != 2 or not np.all(np.isfinite(z)):
        raise ValueError(f"truth must be a finite (rows, cols) array, got shape {z.shape}")
    k = max(3, round(density * z.size))
    sq = np.zeros_like(z)
    for _ in range(layouts):
        r, c = np.divmod(uniform_layout(z.shape, k, rng=rng), z.shape[1])
        sq += (reconstruct(np.column_stack((r, c)), z[r, c], z.shape) - z) ** 2
    sq = ndimage.gaussian_filter(sq / layouts, 0.5 * pitch_of(density), mode="nearest")
    eps = 1e-6 * float(sq.mean()) + 1e-30
    return np.log(sq + eps).astype(np.float32)


def _check_examples(examples) -> list[tuple[np.ndarray, np.ndarray]]:
    out = []
    for i, pair in enumerate(examples):
        image, truth = pair
        img = check_image(image, name=f"examples[{i}] image")
        z = np.asarray(truth, dtype=np.float64)
        if z.shape != img.shape[:2] or not np.all(np.isfinite(z)):
            raise ValueError(
                f"examples[{i}] truth must be finite with the image's shape {img.shape[:2]}, "
                f"got {z.shape}"
            )
        out.append((img, z))
    if len(out) < 1:
        raise ValueError("train_learned_map needs at least one (image, truth) example")
    return out


def _training_set(examples, density, options, rng):
    """Features and centred targets of ``options.pixels_per_example`` pixels per example."""
    xs, ys = [], []
    pitch = pitch_of(density)
    for image, truth in examples:
        y = error_target(truth, density=density, layouts=options.layouts, rng=rng).ravel()
        x = image_features(image, pitch=pitch).reshape(y.size, -1)
        take = rng.choice(y.size, min(options.pixels_per_example, y.size), replace=False)
        xs.append(x[take])
        ys.append(y[take] - y.mean())
    return np.concatenate(xs), np.concatenate(ys)


def train_learned_map(
    examples: Sequence[tuple[np.ndarray, np.ndarray]],
    *,
    densities: Sequence[float],
    options: LearnedOptions | None = None,
    rng,
    provenance: dict | None = None,
) -> LearnedMap:
    """Learn one importance model per density from rendered (image, truth) examples.

    Parameters
    ----------
    examples : sequence of (image, truth)
        image (rows, cols) or (rows, cols, 3) guide image; truth (rows, cols) true depth (m).
        Shapes may differ between examples.
    densities : sequence of float in (0, 1]
        Sample fractions k / N to train a model for (distinct).
    options : LearnedOptions, optional
    rng : None, int, SeedSequence or Generator
        Draws the target layouts, the training pixels and the boosting's seed.
    provenance : dict, optional
        JSON-serialisable description of where the examples came from (the training YAML,
        presets, seeds, sun angles); saved with the model.

    Returns
    -------
    LearnedMap
    """
    opt = options or LearnedOptions()
    rng = np.random.default_rng(rng)
    ex = _check_examples(examples)
    dens = sorted({float(d) for d in densities})
    if not dens or len(dens) != len(list(densities)):
        raise ValueError(f"densities must be distinct and non-empty, got {list(densities)}")
    for d in dens:
        pitch_of(d)
    t0 = time.perf_counter()
    models = {}
    for d in dens:
        x, y = _training_set(ex, d, opt, rng)
        model = HistGradientBoostingRegressor(
            max_iter=opt.max_iter,
            learning_rate=opt.learning_rate,
            max_leaf_nodes=opt.max_leaf_nodes,
            min_samples_leaf=opt.min_samples_leaf,
            l2_regularization=opt.l2_regularization,
            early_stopping=False,
            random_state=int(rng.integers(2**31 - 1)),
        )
        with threadpool_limits(opt.threads):
            models[d] = model.fit(x, y)
    meta = {
        "format": FORMAT,
        "feature_set_version": FEATURE_SET_VERSION,
        "feature_names": list(FEATURE_NAMES),
        "densities": dens,
        "options": asdict(opt),
        "examples": len(ex),
        "input_sha256": [[_sha256_array(i), _sha256_array(t)] for i, t in ex],
        "train_seconds": round(time.perf_counter() - t0, 3),
        "versions": _versions(),
        "provenance": provenance or {},
    }
    json.dumps(meta)  # fail here, not at save time, on a provenance JSON cannot hold
    return LearnedMap(models, meta)
