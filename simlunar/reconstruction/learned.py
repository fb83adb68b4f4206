"""The ``learned`` reconstruction: a residual model that corrects Delaunay-linear with the image.

The Delaunay-linear reconstruction z_lin of the samples (the paper's, section 4.1) misses the
relief between samples; the guide image shows some of it (paper eq. 3.5: I ~ a + b (s . grad z)
on dry, barren terrain under one sun). A regression learns the residual ``truth - z_lin`` per
pixel from what a reconstruction may see, on rendered training terrains:

- the guide image's feature stack at the sample pitch
  (:func:`simlunar.features._stack.image_features`: 42 multi-scale energies, local statistics,
  shadow, border distance), plus signed image features the stack (made for *where* the error
  lies, so all energies) lacks: the image minus its Gaussian blur at half, one and two pitches,
  and its Gaussian derivatives along rows and columns at 1 px and half a pitch;
- from the samples: z_lin's detail (z_lin minus its blur at one pitch), its slope along rows and
  columns and its magnitude, its Laplacian at half a pitch, the local leave-one-out residual of
  the samples (each sample against the plane through its Delaunay neighbours, interpolated
  linearly: how wrong linear is around here), the distance to the nearest sample in pitches,
  and log2 of the density k / N;
- optionally (training option ``with_shading``) the detail of the registered ``shading``
  reconstruction, ``z_shading - z_lin`` (integrated slope along the sun, anchored to the
  samples).

Heights enter in units of h, the RMS leave-one-out residual of the samples (an estimate, from
the samples alone, of linear's error at this layout), and slopes over one pitch, so one model
serves terrains of any relief and any density. **One model for all densities, density a
feature**: with heights in units of h and distances in pitches the residual's relation to the
features changes little with density (unlike the learned map's *log error*, whose structure
changes, :mod:`simlunar.features.learned`), so the densities pool their training pixels into
one model and any density between them is served without a nearest-density switch.

At reconstruction: ``z = z_lin + h r - L(h r at the samples)``, r the predicted residual and L
the Delaunay-linear interpolation, so every measured cell keeps its measured value (a sample at
a non-integer position reads r bilinearly).

**When the image does not help** (option ``heldout_check``, on by default): the residual gets
the held-out check of the ``shading`` reconstruction
(:func:`simlunar.reconstruction.heldout.heldout_gamma`): every fifth sample is left out, the
residual is predicted again from the other samples alone, and the least-squares weight of its
re-anchored detail on the left-out samples (in [0, 1]) weighs the residual inside the samples'
hull (:func:`simlunar.reconstruction.heldout.blend_detail`; linear's nearest fill outside).
Where one split leaves fewer than 20 samples inside the hull (sparse layouts), the five splits
are pooled (every sample left out once, five more predictions) instead of falling back to
linear. Measured on quarter-scale aerial_1 (experiment seed 11, 2 terrains, uniform Lloyd,
1/64-1/2048; experiments/fusion_oracle_quarter.yaml): without the check 1.68x under the 30 deg
sun and 0.95x under camera-centred light; with one split 1.39x and 1.00x (the two sparsest
densities fell back to linear); with the pooled splits 1.60x and 1.00x.
A model trained under a 30 deg sun and asked under camera-centred light (the image is albedo)
measured 0.95x linear's samples at equal MSE on quarter-scale aerial_1 without the check. The
check's predictions are made at the samples' cells alone (all it reads of them): it costs the
features of the kept samples (~9 s at 1000 x 1600 cells), not a second full-grid prediction.

Measured in the project's exploratory runs (quarter-scale aerial presets, 30 deg sun, uniform Lloyd
layouts, samples saved at equal MSE vs linear, geometric mean over 1/64-1/2048): a
gradient-boosting residual on image features 1.65x (aerial_1) / 2.05x (aerial_3); with the
integrated slope as a feature 1.85x / 2.41x.

Model files are results, as the learned map's: ``name.joblib`` beside ``name.json`` (training
options, densities, feature names, library versions, hashes of the training inputs, the joblib
file's SHA-256). :meth:`LearnedReconstruction.load` checks the record (format, feature names,
scikit-learn version, SHA-256) **before** unpickling; unpickling runs code, so load only model
files you made. scikit-learn and joblib are imported on use, not with this module.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np

from simlunar.features._stack import (
    FEATURE_SET_VERSION,
    _model_path,
    _sha256_file,
)
from simlunar.features.model_save import ModelRecord, check_record_matches
from simlunar.reconstruction._anchor import cell_indices, linear_field
from simlunar.reconstruction.base import Reconstructed
from simlunar.reconstruction.delaunay import _check_inputs, reconstruct
from simlunar.reconstruction.heldout import blend_detail, heldout_gamma
from simlunar.reconstruction.learned_features import (
    anchor,
    feature_names,
    residual_features,
    sample_scale,
    shading_heights,
)
from simlunar.registry import FileOption, Options, option

__all__ = [
    "FORMAT",
    "RECON_FEATURE_VERSION",
    "LearnedReconOptions",
    "LearnedReconstruction",
    "anchor",
    "check_model_file",
    "feature_names",
    "learned_reconstruction",
    "residual_features",
    "sample_scale",
    "shading_heights",
]

#: identifies the JSON record of a learned-reconstruction model file
FORMAT = "simlunar-learned-reconstruction/1"

#: bump whenever a feature below (not the image stack: that has its own version) changes
RECON_FEATURE_VERSION = 1


@dataclass(frozen=True)
class LearnedReconOptions(Options):
    """Options of the ``learned`` reconstruction."""

    model: str = option(
        "",
        doc="model file (.joblib, its .json record beside it) made by `simlunar train` with "
        "target: reconstruction (required)",
        file=FileOption("model", FORMAT),
    )
    threads: int = option(1, doc="OpenMP threads of the prediction", ge=1, le=64)
    heldout_check: bool = option(
        True,
        doc="weigh the residual by the shading reconstruction's held-out check: every fifth "
        "sample is left out, the residual predicted from the others, and its least-squares "
        "weight on the left-out samples caps the blend (never clearly worse than linear)",
        choices=(True, False),
    )

    def __post_init__(self):
        if not isinstance(self.model, (str, Path)):
            raise ValueError(f"model must be a path to a .joblib file, got {self.model!r}")
        object.__setattr__(self, "model", str(self.model))
        if isinstance(self.threads, bool) or not isinstance(self.threads, int):
            raise ValueError(f"threads must be an integer, got {self.threads!r}")
        super().__post_init__()


@dataclass(frozen=True, eq=False)
class LearnedReconstruction(ModelRecord):
    """A trained residual model and its record (:class:`~simlunar.features.model_save.ModelRecord`).

    Attributes
    ----------
    model : HistGradientBoostingRegressor
        Residual / h from :func:`feature_names` (``meta["with_shading"]``).
    meta : dict
        The JSON record.
    """

    FORMAT: ClassVar[str] = FORMAT
    model: object
    meta: dict = field(default_factory=dict)

    @property
    def with_shading(self) -> bool:
        return bool(self.meta.get("with_shading", False))

    def reconstruct(
        self, points_rc, values, shape, *, guide, threads: int = 1, heldout_check: bool = True
    ) -> Reconstructed:
        """Linear + predicted residual, anchored to the samples.

        Parameters
        ----------
        points_rc : array_like, shape (k, 2)
        values : array_like, shape (k,)
        shape : tuple of int
            (rows, cols), the guide image's shape.
        guide : Guide
        threads : int
            OpenMP threads of the prediction.
        heldout_check : bool
            Weigh the residual by the held-out check of the ``shading`` reconstruction
            (:func:`simlunar.reconstruction.heldout.heldout_gamma`: every fifth sample left
            out, the residual predicted again from the others, and the least-squares weight
            of its re-anchored detail on the left-out samples caps the blend; where one split
            leaves fewer than 20 samples, all five splits are pooled,
            :func:`simlunar.reconstruction.heldout.blend_detail`). Off: the full residual
            (the model as trained; outside the samples' hull too), as before the check.

        Returns
        -------
        Reconstructed
            heights float64 (rows, cols); info: ``scale_m`` (h), ``residual_rms_m`` (RMS of
            the correction added to linear), ``model_sha256`` (first 12 hex digits) and, with
            the check, ``gamma`` (the residual's weight), ``heldout_gamma`` and
            ``heldout_samples`` (the check's weight and the left-out samples it used).
        """
        shape = tuple(int(s) for s in shape)
        if guide.shape != shape:
            raise ValueError(f"guide image has shape {guide.shape}, the output grid {shape}")
        pts, vals, _ = _check_inputs(points_rc, values, shape)
        r, h, z_lin = self._residual(pts, vals, shape, guide, threads)
        info = {"scale_m": h, "model_sha256": self.model_sha256[:12]}
        if h == 0:  # every sample on its neighbours' plane: nothing for a residual to scale
            if heldout_check:
                info.update(gamma=0.0, heldout_gamma=0.0, heldout_samples=0)
            return Reconstructed(z_lin, {**info, "residual_rms_m": 0.0})
        if not heldout_check:
            z = anchor(z_lin, r, pts)
        else:
            lin = linear_field(pts, vals, shape)
            # the check reads each remade residual only at the samples (kept and left out):
            # predict it there alone (a full-grid prediction is ~25 s per fold at 1.6 M cells)
            cells = _sample_cells(pts, shape)
            g, n = heldout_gamma(
                lambda keep: self._residual(
                    keep.points, keep.values, shape, guide, threads, only=cells
                )[0],
                lin,
                pool_folds=True,
            )
            info.update(gamma=g, heldout_gamma=g, heldout_samples=n)
            z = blend_detail(lin, r, g) if g > 0 else lin.heights
        info["residual_rms_m"] = float(np.sqrt(np.mean((z - z_lin) ** 2)))
        return Reconstructed(z, info)

    def _residual(self, pts, vals, shape, guide, threads, only=None):
        """``(h r, h, z_lin)``: the predicted residual in value units (zeros when h = 0), the
        height unit and the linear reconstruction of these samples. ``only`` (flat cell
        indices): predict those cells alone, NaN elsewhere (each cell's prediction is its
        own, so they are the values a full prediction gives there)."""
        from threadpoolctl import threadpool_limits

        z_lin = reconstruct(pts, vals, shape)
        shade = None
        if self.with_shading:
            shade = shading_heights(
                pts, vals, shape, guide=guide, options=self.meta.get("shading_options")
            )
        x, h, z_lin = residual_features(guide.image, pts, vals, z_lin=z_lin, shading=shade)
        if h == 0:
            return np.zeros(shape), h, z_lin
        with threadpool_limits(int(threads)):
            if only is None:
                r = self.model.predict(x).reshape(shape) * h
            else:
                r = np.full(shape, np.nan)
                r.flat[only] = self.model.predict(x[only]) * h
        return r, h, z_lin

    def _payload(self) -> dict:
        return {"model": self.model}

    @classmethod
    def load(cls, path) -> LearnedReconstruction:
        """Load a model saved by :meth:`save`, after checking its record.

        Refuses (one-line ``ValueError`` naming the file) a missing or unreadable record,
        another format or feature set, another scikit-learn version (pickles do not carry
        across versions) and a joblib file whose SHA-256 differs from the record's (a
        truncated or replaced file), all before unpickling.
        """
        path, _ = check_model_file(path)
        return cls.from_bytes(path.read_bytes(), path.with_suffix(".json").read_bytes(), path=path)

    @classmethod
    def from_bytes(cls, data: bytes, record: bytes, *, path) -> LearnedReconstruction:
        """A model from the bytes of its joblib file and of its JSON record: the record's
        checks (:func:`check_model_file`) on these bytes, then the unpickling, whose every
        failure (a text file renamed ``.joblib`` whose record carries its true hash, another
        library) is a one-line ``ValueError`` naming the file."""
        import hashlib

        path = Path(path)
        meta = _record_meta(record, path)
        check_record_matches(meta, path, hashlib.sha256(data).hexdigest())
        import io

        import joblib

        try:
            payload = joblib.load(io.BytesIO(data))
        except Exception as e:  # the hash matched, so this is a library mismatch or no pickle
            msg = " ".join(str(e).split())
            raise ValueError(f"{path}: cannot be read back ({type(e).__name__}: {msg})") from None
        if not isinstance(payload, dict) or payload.get("format") != FORMAT:
            raise ValueError(f"{path}: not a {FORMAT} model file")
        if not callable(getattr(payload.get("model"), "predict", None)):
            raise ValueError(f"{path}: its payload holds no regressor (no predict)")
        return cls._loaded(payload["model"], meta)


def _sample_cells(pts: np.ndarray, shape) -> np.ndarray | None:
    """Flat indices of the samples' cells, or None unless every sample sits on a cell centre
    inside the grid (off-centre samples are read bilinearly, from neighbours too)."""
    cells = cell_indices(pts, shape)
    return None if cells is None else np.unique(np.ravel_multi_index(cells, shape))


def check_model_file(path) -> tuple[Path, dict]:
    """The model file and its parsed record, after every check that needs no unpickling.

    What :meth:`LearnedReconstruction.load` checks before it unpickles (a preflight can call it
    to refuse a bad model file before any work): one-line ``ValueError`` naming the file.

    Parameters
    ----------
    path : str or Path
        A ``.joblib`` model file.

    Returns
    -------
    (Path, dict)
        The path and its JSON record.
    """

    path = _model_path(path)
    sidecar = path.with_suffix(".json")
    if not path.is_file() or not sidecar.is_file():
        raise ValueError(f"learned reconstruction {path} needs both {path.name} and {sidecar.name}")
    meta = _record_meta(sidecar.read_bytes(), path)
    check_record_matches(meta, path, _sha256_file(path))
    return path, meta


def _record_meta(record: bytes, path: Path) -> dict:
    """The parsed JSON record of the model file ``path``, after the checks of its format and
    feature set (one-line ``ValueError`` naming the file)."""
    sidecar = Path(path).with_suffix(".json")
    try:
        meta = json.loads(record.decode("utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise ValueError(f"{sidecar}: not a readable JSON record ({e})") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        got = meta.get("format") if isinstance(meta, dict) else None
        raise ValueError(f"{path}: not a {FORMAT} model (format {got!r})")
    want = list(feature_names(bool(meta.get("with_shading"))))
    if (
        meta.get("feature_names") != want
        or meta.get("recon_feature_version") != RECON_FEATURE_VERSION
        or meta.get("feature_set_version") != FEATURE_SET_VERSION
    ):
        raise ValueError(
            f"{path}: trained on another feature set (version {meta.get('recon_feature_version')!r}"
            f", image stack {meta.get('feature_set_version')!r}; this simlunar computes "
            f"{RECON_FEATURE_VERSION}, {FEATURE_SET_VERSION}): retrain the model"
        )
    return meta


_CACHE: dict[tuple[str, str], LearnedReconstruction] = {}


def _cached(model) -> LearnedReconstruction:
    """The model file ``model``, loaded once per (resolved path, SHA-256 of the file)."""
    path = _model_path(model).resolve()
    if not path.is_file():
        raise ValueError(f"learned reconstruction model file not found: {model}")
    key = (str(path), _sha256_file(path))
    if key not in _CACHE:
        loaded = LearnedReconstruction.load(path)
        if len(_CACHE) >= 4:
            _CACHE.clear()
        _CACHE[key] = loaded
    return _CACHE[key]


def learned_reconstruction(
    points_rc, values, shape, *, guide=None, options: LearnedReconOptions | None = None
) -> Reconstructed:
    """The registered ``learned`` reconstruction: :meth:`LearnedReconstruction.reconstruct` of
    the model file ``options.model`` (loaded once per path and file hash).

    Parameters
    ----------
    points_rc : array_like, shape (k, 2)
    values : array_like, shape (k,)
    shape : tuple of int
    guide : Guide
        Required (the image is the model's main input).
    options : LearnedReconOptions
        ``model`` is required.

    Returns
    -------
    Reconstructed
    """
    o = options or LearnedReconOptions()
    if not o.model:
        raise ValueError(
            "reconstruction 'learned' needs option 'model': a .joblib file made by "
            "`simlunar train <yaml>` with target: reconstruction"
        )
    if guide is None:
        raise ValueError("reconstruction 'learned' needs the guide image (guide=Guide(...))")
    return _cached(o.model).reconstruct(
        points_rc, values, shape, guide=guide, threads=o.threads, heldout_check=o.heldout_check
    )
