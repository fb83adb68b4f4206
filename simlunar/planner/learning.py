"""Training the learned importance map (the paper's "learn a mapping", section 3.1): the
target is where a uniform layout's reconstruction error lies; the model
(:class:`simlunar.features.learned.LearnedMap`) then predicts it from the guide image alone.
And training the learned reconstruction (:mod:`simlunar.reconstruction.learned`): the target
is the residual truth - linear of uniform layouts.

Training lives in ``planner/`` because its targets are made with layouts and a reconstruction;
the predictions (``features.learned``, ``reconstruction.learned``) need no layout.
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass

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
from simlunar.progress import stage
from simlunar.reconstruction import RECONSTRUCTIONS, Guide, run_reconstruction
from simlunar.reconstruction import reconstruct as reconstruct_linear
from simlunar.reconstruction.learned import FORMAT as RECON_FORMAT
from simlunar.reconstruction.learned import (
    RECON_FEATURE_VERSION,
    LearnedReconstruction,
    feature_names,
    residual_features,
    shading_heights,
)

__all__ = ["error_target", "train_learned_map", "train_learned_reconstruction"]


def error_target(
    truth, *, density: float, layouts: int = 3, rng=None, reconstruct=None
) -> np.ndarray:
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
    reconstruct : callable, optional
        ``reconstruct(rc, values) -> heights`` (rc (k, 2) int64, values (k,) the truth there,
        heights (rows, cols)): the reconstruction whose error is the target, e.g. the fused
        ``shading`` reconstruction with the example's guide ("sample where the camera cannot
        tell"); default Delaunay-linear (the paper's).

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
        rc = np.column_stack((r, c))
        rec = reconstruct_linear(rc, z[r, c], z.shape) if reconstruct is None else (
            np.asarray(reconstruct(rc, z[r, c]), dtype=np.float64))  # fmt: skip
        sq += (rec - z) ** 2
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


def _checked_densities(densities) -> list[float]:
    """The sorted densities; ValueError when empty, repeated or any has no sample pitch."""
    dens = sorted({float(d) for d in densities})
    if not dens or len(dens) != len(list(densities)):
        raise ValueError(f"densities must be distinct and non-empty, got {list(densities)}")
    for d in dens:
        pitch_of(d)
    return dens


def _fit_boosted(x, y, opt, rng) -> HistGradientBoostingRegressor:
    """A histogram gradient-boosting regressor with ``opt``'s settings fitted to ``(x, y)``.

    Parameters
    ----------
    x : ndarray, shape (n, features)
    y : ndarray, shape (n,)
    opt : LearnedOptions
    rng : Generator
        Draws the boosting's seed (one integer).
    """
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
        return model.fit(x, y)


def _training_meta(head, dens, opt, ex, t0, provenance, **counts) -> dict:
    """The JSON record of a training: ``head`` (format and features), then the densities,
    options, example count, ``counts``, input hashes, seconds since ``t0``, library versions
    and ``provenance``. A record JSON cannot hold fails here (``TypeError``), not at save time."""
    meta = {
        **head,
        "densities": dens,
        "options": asdict(opt),
        "examples": len(ex),
        **counts,
        "input_sha256": [[_sha256_array(i), _sha256_array(t)] for i, t in ex],
        "train_seconds": round(time.perf_counter() - t0, 3),
        "versions": _versions(),
        "provenance": provenance or {},
    }
    json.dumps(meta)  # fail here, not at save time, on a provenance JSON cannot hold
    return meta


def _training_set(examples, density, options, rng, reconstructors=None):
    """Features and centred targets of ``options.pixels_per_example`` pixels per example
    (the target: the error of each example's ``reconstructors`` entry, None: linear)."""
    xs, ys = [], []
    pitch = pitch_of(density)
    fns = reconstructors or [None] * len(examples)
    for (image, truth), fn in zip(examples, fns, strict=True):
        y = error_target(
            truth, density=density, layouts=options.layouts, rng=rng, reconstruct=fn
        ).ravel()
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
    error_reconstruction: str = "linear",
    reconstruction_options=None,
    guides: Sequence[Guide] | None = None,
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
    error_reconstruction : str
        The registered reconstruction (:data:`simlunar.reconstruction.RECONSTRUCTIONS`)
        whose error is the target: ``linear`` (the paper's, the default: the model and its
        record as before) or e.g. ``shading``, the fused model: the map then learns where
        the reconstruction that reads the image still errs ("sample where the camera cannot
        tell": shadows, albedo edges, weak shading). Recorded in the model's record
        (``error_reconstruction``, its options and the guide frames it read).
    reconstruction_options : options object or mapping, optional
        Its options (defaults when None).
    guides : sequence of Guide, optional
        What the camera saw in each example, for a guided reconstruction (one per example,
        on its grid); default ``Guide(image)`` (the example's image, light unknown).

    Returns
    -------
    LearnedMap
    """
    opt = options or LearnedOptions()
    rng = np.random.default_rng(rng)
    ex = _check_examples(examples)
    dens = _checked_densities(densities)
    fns, recorded = _error_reconstructors(ex, error_reconstruction, reconstruction_options,
                                          guides)  # fmt: skip
    t0 = time.perf_counter()
    models = {}
    with stage("fitting", total=len(dens), unit="densities") as fitted:
        for d in dens:
            x, y = _training_set(ex, d, opt, rng, fns)
            models[d] = _fit_boosted(x, y, opt, rng)
            fitted.advance()
    head = {
        "format": FORMAT,
        "feature_set_version": FEATURE_SET_VERSION,
        "feature_names": list(FEATURE_NAMES),
        **recorded,
    }
    return LearnedMap(models, _training_meta(head, dens, opt, ex, t0, provenance))


def _error_reconstructors(examples, name, options, guides) -> tuple[list | None, dict]:
    """Per example the ``(rc, values) -> heights`` of reconstruction ``name`` (None for all
    when it is ``linear`` with its defaults: the target of before) and what the record says of
    it (nothing for linear: the record of before)."""
    entry, opts = RECONSTRUCTIONS.resolve(name, options)  # unknown name: a ValueError
    if guides is not None and len(guides) != len(examples):
        raise ValueError(f"guides: one per example ({len(examples)}), got {len(guides)}")
    if name == "linear" and opts == entry.make_options({}):
        if guides is not None:
            raise ValueError("guides are for a guided error_reconstruction, not linear")
        return None, {}
    guided = bool(entry.meta.get("guided"))
    if guides is None:
        guides = [Guide(image) for image, _ in examples] if guided else [None] * len(examples)
    for i, (g, (image, _)) in enumerate(zip(guides, examples, strict=True)):
        if guided and (g is None or g.shape != image.shape[:2]):
            raise ValueError(f"guides[{i}]: a Guide on the example's grid {image.shape[:2]}")
    fns = [_Recon(name, opts, truth.shape, g) for (_, truth), g in zip(examples, guides)]
    frames = sorted({f for g in guides if g is not None for f in g.frames})
    recorded = {
        "error_reconstruction": name,
        "error_reconstruction_options": asdict(opts),
        "error_guide_frames": frames if guided else [],
    }
    return fns, recorded


@dataclass(frozen=True, eq=False)
class _Recon:
    """``(rc, values) -> heights`` of one registered reconstruction on one example."""

    name: str
    options: object
    shape: tuple
    guide: object

    def __call__(self, rc, values):
        return run_reconstruction(
            self.name, rc, values, self.shape, guide=self.guide, options=self.options
        ).heights


def _recon_training_set(examples, densities, options, with_shading, shading_options, rng):
    """Features and residual / h targets: ``options.pixels_per_example`` pixels per example and
    density, spread over ``options.layouts`` uniform Lloyd layouts."""
    xs, ys = [], []
    with stage("training set", total=len(examples), unit="examples") as done:
        for image, truth in examples:
            x, y = _example_rows(image, truth, densities, options, with_shading, shading_options,
                                 rng)  # fmt: skip
            xs += x
            ys += y
            done.advance()
    if not xs:
        raise ValueError("every training layout's samples lie on planes: nothing to learn")
    return np.concatenate(xs), np.concatenate(ys)


def _example_rows(image, truth, densities, options, with_shading, shading_options, rng):
    """One example's features and targets: ``(xs, ys)``, lists of arrays (one per layout)."""
    xs, ys = [], []
    guide = Guide(image) if with_shading else None
    n = truth.size
    for d in densities:
        k = max(4, round(d * n))
        for j in range(options.layouts):
            r, c = np.divmod(uniform_layout(truth.shape, k, rng=rng), truth.shape[1])
            pts = np.column_stack((r, c))
            vals = truth[r, c]
            shade = None
            if with_shading:
                shade = shading_heights(
                    pts, vals, truth.shape, guide=guide, options=shading_options
                )
            x, h, z_lin = residual_features(image, pts, vals, shading=shade)
            if h == 0:  # linear is exact on these samples: no residual to learn
                continue
            y = ((truth - z_lin) / h).ravel()
            share = options.pixels_per_example // options.layouts
            share += j < options.pixels_per_example % options.layouts
            take = rng.choice(n, min(share, n), replace=False)
            xs.append(x[take])
            ys.append(y[take])
    return xs, ys


def train_learned_reconstruction(
    examples: Sequence[tuple[np.ndarray, np.ndarray]],
    *,
    densities: Sequence[float],
    options: LearnedOptions | None = None,
    with_shading: bool = False,
    shading_options: dict | None = None,
    rng,
    provenance: dict | None = None,
):
    """Learn the residual model of the ``learned`` reconstruction from rendered examples.

    For every example, density and layout (``options.layouts`` uniform Lloyd layouts,
    :func:`simlunar.planner.sequential.uniform_layout`) the truth is sampled at the layout's
    cells, reconstructed by Delaunay-linear, and ``options.pixels_per_example / layouts``
    pixels drawn uniformly contribute their features
    (:func:`simlunar.reconstruction.learned.residual_features`) and target (truth - z_lin) / h.
    One ``HistGradientBoostingRegressor`` (squared error, no early stopping, seeded) fits all
    densities together, log2 density being a feature.

    Parameters
    ----------
    examples : sequence of (image, truth)
        image (rows, cols) or (rows, cols, 3) guide image; truth (rows, cols) true depth or
        height (m). Shapes may differ between examples.
    densities : sequence of float in (0, 1]
        Sample fractions k / N of the training layouts (distinct).
    options : LearnedOptions, optional
        Layouts, pixels and boosting settings (shared with the learned map).
    with_shading : bool
        Add the feature ``shading_detail`` of the registered ``shading`` reconstruction
        (a ``ValueError`` if none is registered); the model then needs it at reconstruction.
    shading_options : dict, optional
        Options of the ``shading`` reconstruction (recorded, and used again at
        reconstruction).
    rng : None, int, SeedSequence or Generator
        Draws the layouts, the training pixels and the boosting's seed.
    provenance : dict, optional
        JSON-serialisable description of the examples' origin; saved with the model.

    Returns
    -------
    simlunar.reconstruction.learned.LearnedReconstruction
    """
    opt = options or LearnedOptions()
    rng = np.random.default_rng(rng)
    ex = _check_examples(examples)
    dens = _checked_densities(densities)
    if shading_options and not with_shading:
        raise ValueError("shading_options given without with_shading=True")
    if with_shading:
        if "shading" not in RECONSTRUCTIONS:
            raise ValueError(
                "with_shading needs the reconstruction 'shading', which is not registered "
                f"(have: {', '.join(RECONSTRUCTIONS)})"
            )
        RECONSTRUCTIONS["shading"].make_options(shading_options)  # bad keys fail before work
    t0 = time.perf_counter()
    x, y = _recon_training_set(ex, dens, opt, with_shading, shading_options, rng)
    with stage("fitting", total=1, unit="models") as fitted:
        model = _fit_boosted(x, y, opt, rng)
        fitted.advance()
    head = {
        "format": RECON_FORMAT,
        "recon_feature_version": RECON_FEATURE_VERSION,
        "feature_set_version": FEATURE_SET_VERSION,
        "feature_names": list(feature_names(with_shading)),
        "with_shading": bool(with_shading),
        "shading_options": dict(shading_options or {}),
    }
    meta = _training_meta(head, dens, opt, ex, t0, provenance, training_pixels=len(y))
    return LearnedReconstruction(model, meta)
