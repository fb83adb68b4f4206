"""The paper's learned mapping (section 3.1): a learned importance map from image features.

"Determine features from intensity images and learn a mapping" to where samples matter. A
simulator renders terrains with exact depth, so the mapping is learned by regression:

- inputs: :func:`simlunar.features._stack.image_features` of the guide image only (42 features:
  multi-scale wavelet, gradient and LoG energies, local mean and spread, intensity, shadow,
  border distance, and pitch-smoothed copies);
- target (:func:`simlunar.planner.learning.error_target`): where a uniform layout's reconstruction error lies: the log of
  the squared error of a uniform layout's Delaunay-linear reconstruction, averaged over a few
  layouts and smoothed at half the pitch, centred per example (only the map's shape matters to
  a planner, not the terrain's overall roughness);
- model: one scikit-learn ``HistGradientBoostingRegressor`` per density. The error's structure
  changes with density (texture at dense sampling, crater rims and the border at sparse), the
  features are computed at that density's pitch anyway, and independent models are simple to
  train, inspect and extend; an untrained density uses the model of the nearest trained density
  in log density, with features at the requested pitch.

:meth:`LearnedMap.predict` returns the predicted smoothed squared error exp(prediction), an
importance map >= 0 to place with a density E^(1/2) (measured in ``shared/REFERENCES.md``:
Spearman 0.37-0.58 against the true error at 1/64 vs the wavelet energy's 0.17-0.35).

A model file is a result: ``name.joblib`` (the regressors) beside ``name.json`` (training
options, densities, feature set, library versions, hashes of the training inputs, the SHA-256
of the joblib file and the caller's provenance). **Loading a joblib file unpickles it, which
runs code**: load only models you made. :meth:`LearnedMap.load` checks the JSON's feature-set
version and library versions and the joblib file's hash *before* unpickling.
"""

from __future__ import annotations

import hashlib
import json
import platform
from dataclasses import dataclass, field
from pathlib import Path

import joblib
import numpy as np
import pywt
import scipy
import sklearn
from threadpoolctl import threadpool_limits

from simlunar import __version__ as simlunar_version
from simlunar.features._stack import (
    FEATURE_NAMES,
    FEATURE_SET_VERSION,
    _model_path,
    _sha256_file,
    image_features,
)
from simlunar.features.maps import check_image

__all__ = [
    "FORMAT",
    "LearnedMap",
    "LearnedOptions",
    "learned",
    "pitch_of",
    "save_with_record",
]

#: identifies the JSON sidecar of a model file
FORMAT = "simlunar-learned-map/1"


def pitch_of(density: float) -> float:
    """Sample spacing in pixels of a density k / N: density^(-1/2)."""
    if not 0.0 < density <= 1.0:
        raise ValueError(f"density must be in (0, 1], got {density!r}")
    return float(density) ** -0.5


@dataclass(frozen=True)
class LearnedOptions:
    """Training options of :func:`simlunar.planner.learning.train_learned_map`.

    Attributes
    ----------
    layouts : int >= 1
        Uniform layouts whose squared errors are averaged into each target.
    pixels_per_example : int >= 100
        Training pixels drawn (uniformly, without replacement) per example and density.
    max_iter, max_leaf_nodes, min_samples_leaf : int
        ``HistGradientBoostingRegressor`` settings (boosting rounds, tree size, leaf size).
    learning_rate : float > 0
    l2_regularization : float >= 0
    threads : int >= 1
        OpenMP threads of the boosting (fit and predict). Default 1: on a shared machine
        scikit-learn's OpenMP threads wait on each other (measured: 96 k x 42 features, 100
        rounds, 2 cores under load 8: 10 s with one thread, 107 s with two); raise it on an idle
        machine.
    """

    layouts: int = 3
    pixels_per_example: int = 10_000
    max_iter: int = 200
    max_leaf_nodes: int = 31
    min_samples_leaf: int = 50
    learning_rate: float = 0.1
    l2_regularization: float = 0.0
    threads: int = 1

    def __post_init__(self):
        for name, lo in (
            ("layouts", 1),
            ("pixels_per_example", 100),
            ("threads", 1),
            ("max_iter", 1),
            ("max_leaf_nodes", 2),
            ("min_samples_leaf", 1),
        ):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < lo:
                raise ValueError(f"{name} must be an integer >= {lo}, got {v!r}")
        if not self.learning_rate > 0:
            raise ValueError(f"learning_rate must be > 0, got {self.learning_rate!r}")
        if not self.l2_regularization >= 0:
            raise ValueError(f"l2_regularization must be >= 0, got {self.l2_regularization!r}")


def _sha256_array(a: np.ndarray) -> str:
    a = np.ascontiguousarray(a)
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())
    return h.hexdigest()


def _versions() -> dict[str, str]:
    return {
        "simlunar": simlunar_version,
        "scikit-learn": sklearn.__version__,
        "joblib": joblib.__version__,
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "PyWavelets": pywt.__version__,
        "python": platform.python_version(),
    }


@dataclass(frozen=True, eq=False)
class LearnedMap:
    """Trained importance models, one per density, and their record.

    Attributes
    ----------
    models : dict of float -> HistGradientBoostingRegressor
        Density k / N -> regressor of the centred log error on :data:`FEATURE_NAMES`.
    meta : dict
        The JSON record (format, feature set, densities, options, input hashes, versions,
        provenance).
    """

    models: dict
    meta: dict = field(default_factory=dict)

    @property
    def densities(self) -> list[float]:
        """Trained densities, ascending."""
        return sorted(self.models)

    def model_for(self, density: float):
        """The regressor of the trained density nearest ``density`` in log density."""
        pitch_of(density)
        d = min(self.densities, key=lambda t: abs(np.log(t) - np.log(density)))
        return self.models[d]

    def predict_log(self, image, *, density: float) -> np.ndarray:
        """Predicted centred log error, float64 (rows, cols)."""
        img = check_image(image)
        x = image_features(img, pitch=pitch_of(density))
        with threadpool_limits(int(self.meta.get("options", {}).get("threads", 1))):
            y = self.model_for(density).predict(x.reshape(-1, x.shape[-1]))
        return y.reshape(img.shape[:2])

    def predict(self, image, *, density: float) -> np.ndarray:
        """Importance map: the predicted smoothed squared error, relative (max 1).

        Parameters
        ----------
        image : ndarray, shape (rows, cols) or (rows, cols, 3)
            Guide image.
        density : float in (0, 1]
            Sample fraction k / N the map is for.

        Returns
        -------
        ndarray of float64, shape (rows, cols), in (0, 1]
        """
        y = self.predict_log(image, density=density)
        return np.exp(y - y.max())

    def save(self, path) -> tuple[Path, Path]:
        """Write ``path`` (joblib of the regressors) and its JSON sidecar (``.json``).

        Parameters
        ----------
        path : str or Path
            Model file name ending in ``.joblib``; parent folders are created.

        Returns
        -------
        (Path, Path)
            The joblib file and the JSON sidecar.
        """
        payload = {"format": FORMAT, "models": {repr(d): m for d, m in self.models.items()}}
        return save_with_record(path, payload, self.meta)

    @classmethod
    def load(cls, path) -> LearnedMap:
        """Load a model saved by :meth:`save`, after checking its record.

        Refuses (``ValueError``) a missing sidecar, another format or feature-set version,
        another scikit-learn version (pickles do not carry across versions) and a joblib file
        whose SHA-256 differs from the sidecar's, all before unpickling. Unpickling runs code:
        load only your own results.
        """
        path = _model_path(path)
        sidecar = path.with_suffix(".json")
        if not path.is_file() or not sidecar.is_file():
            raise ValueError(f"learned model {path} needs both {path.name} and {sidecar.name}")
        meta = json.loads(sidecar.read_text())
        _check_meta(meta, path)
        payload = joblib.load(path)
        models = {float(d): m for d, m in payload["models"].items()}
        if sorted(models) != sorted(meta["densities"]):
            raise ValueError(f"learned model {path}: densities differ from its record")
        return cls(models, {k: v for k, v in meta.items() if k not in ("model_file",)})


def save_with_record(path, payload, meta: dict) -> tuple[Path, Path]:
    """Write ``payload`` with joblib to ``path`` and ``meta`` beside it as JSON (``.json``),
    with the model file's name and SHA-256 added: the record a load checks before unpickling.

    Parameters
    ----------
    path : str or Path
        Ends in ``.joblib``; parent folders are created.
    payload : object
        What joblib pickles.
    meta : dict
        The JSON record (not changed).

    Returns
    -------
    (Path, Path)
        The joblib file and its record.
    """
    path = _model_path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    joblib.dump(payload, path)
    meta = {**meta, "model_file": path.name, "model_sha256": _sha256_file(path)}
    sidecar = path.with_suffix(".json")
    sidecar.write_text(json.dumps(meta, indent=2, sort_keys=True) + "\n")
    return path, sidecar


def _check_meta(meta: dict, path: Path) -> None:
    """Refuse a record of another format, feature set or library version, or another file."""
    if meta.get("format") != FORMAT:
        raise ValueError(f"{path}: not a {FORMAT} model (format {meta.get('format')!r})")
    if meta.get("feature_set_version") != FEATURE_SET_VERSION or meta.get("feature_names") != list(
        FEATURE_NAMES
    ):
        raise ValueError(
            f"{path}: trained on feature set version {meta.get('feature_set_version')!r}, this "
            f"simlunar computes version {FEATURE_SET_VERSION}: retrain the model"
        )
    saved = meta.get("versions", {}).get("scikit-learn")
    if saved != sklearn.__version__:
        raise ValueError(
            f"{path}: saved with scikit-learn {saved}, installed {sklearn.__version__}: retrain"
        )
    if _sha256_file(path) != meta.get("model_sha256"):
        raise ValueError(f"{path}: SHA-256 does not match its record (modified or replaced)")


_CACHE: dict[tuple, LearnedMap] = {}


def learned(image, *, model, density: float) -> np.ndarray:
    """The ``learned`` feature map: :meth:`LearnedMap.predict` of the model file ``model``.

    Loaded models are cached by (resolved path, size, modification time).

    Parameters
    ----------
    image : ndarray, shape (rows, cols) or (rows, cols, 3)
    model : str or Path
        A ``.joblib`` model file written by :meth:`LearnedMap.save`.
    density : float in (0, 1]
        Sample fraction k / N the map is for.

    Returns
    -------
    ndarray of float64, shape (rows, cols), in (0, 1]
    """
    path = _model_path(model).resolve()
    try:
        st = path.stat()
    except OSError:
        raise ValueError(f"learned model file not found: {model}") from None
    key = (str(path), st.st_size, st.st_mtime_ns)
    if key not in _CACHE:
        _CACHE.clear()
        _CACHE[key] = LearnedMap.load(path)
    return _CACHE[key].predict(image, density=density)
