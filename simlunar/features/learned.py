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
importance map >= 0 to place with a density E^(1/2) (measured on quarter-scale held-out seeds:
Spearman 0.37-0.58 against the true error at 1/64 vs the wavelet energy's 0.17-0.35).

A model file is a result: ``name.joblib`` (the regressors) beside ``name.json`` (training
options, densities, feature set, library versions, hashes of the training inputs, the SHA-256
of the joblib file and the caller's provenance). **Loading a joblib file unpickles it, which
runs code**: load only models you made. :meth:`LearnedMap.load` checks the JSON's feature-set
version and library versions and the joblib file's hash *before* unpickling.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import hashlib
import io
import json
import math
import os
import platform
import threading
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

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
    image_features,
)
from simlunar.features.maps import check_image
from simlunar.features.model_save import ModelRecord, check_record_matches, save_with_record
from simlunar.registry import Options, option

__all__ = [
    "FORMAT",
    "LearnedMap",
    "LearnedOptions",
    "learned",
    "pinned_models",
    "pitch_of",
    "predict_cores",
    "predict_rows",
    "read_model_bytes",
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
class LearnedOptions(Options):
    """Training options of :func:`simlunar.planner.learning.train_learned_map`.

    ``max_iter``, ``max_leaf_nodes``, ``min_samples_leaf``, ``learning_rate`` and
    ``l2_regularization`` are scikit-learn ``HistGradientBoostingRegressor`` settings. The
    threads default to 1: on a shared machine scikit-learn's OpenMP threads wait on each other
    (measured: 96 k x 42 features, 100 rounds, 2 cores under load 8: 10 s with one thread,
    107 s with two); raise it on an idle machine.
    """

    layouts: int = option(
        3, doc="uniform layouts whose squared errors are averaged into each target", ge=1
    )
    pixels_per_example: int = option(
        10_000,
        doc="training pixels drawn (uniformly, without replacement) per example and density",
        ge=100,
    )
    max_iter: int = option(200, doc="boosting rounds", ge=1)
    max_leaf_nodes: int = option(31, doc="leaves per tree", ge=2)
    min_samples_leaf: int = option(50, doc="training pixels per leaf (at least)", ge=1)
    learning_rate: float = option(0.1, doc="boosting learning rate", gt=0)
    l2_regularization: float = option(0.0, doc="leaf-value L2 penalty", ge=0)
    threads: int = option(1, doc="OpenMP threads of the boosting (fit and predict)", ge=1)

    def __post_init__(self):
        super().__post_init__()
        for name in (
            "layouts",
            "pixels_per_example",
            "max_iter",
            "max_leaf_nodes",
            "min_samples_leaf",
            "threads",
        ):
            if not isinstance(getattr(self, name), int):
                raise ValueError(f"{name} must be an integer, got {getattr(self, name)!r}")


#: rows per chunk below which a prediction stays in the calling thread
PREDICT_CHUNK_ROWS = 200_000


def predict_cores() -> int:
    """The cores this process may run on (its CPU affinity where the system has one)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def predict_rows(regressor, x: np.ndarray, *, threads: int = 1, cores: int | None = None):
    """``regressor.predict(x)``, its rows split over up to ``cores`` (default: this process's
    cores) Python threads, each chunk with ``threads`` OpenMP threads.

    A row's prediction depends on that row alone, so the result is the single call's to the
    bit. scikit-learn's tree traversal releases the GIL: the chunks run in parallel, and on a
    loaded machine they share the cores instead of spinning at an OpenMP barrier as the
    boosting's own threads do (see :class:`LearnedOptions`). On a 971 x 1674 guide (1.6 M
    rows, 42 features, 200 trees) on 2 idle cores: 7.7 s against 15.3 s in one thread (the
    boosting's 2 OpenMP threads: 8.7 s); the learned maps were 63 % of a
    ``table2_moonyard_learned`` unit's time.
    """
    n = max(1, min(cores or predict_cores(), len(x) // PREDICT_CHUNK_ROWS))

    def run(part):
        with threadpool_limits(threads):
            return regressor.predict(part)

    if n == 1:
        return run(x)
    with cf.ThreadPoolExecutor(n, thread_name_prefix="simlunar-predict") as pool:
        return np.concatenate(list(pool.map(run, np.array_split(x, n))))


def _sha256_array(a: np.ndarray) -> str:
    a = np.ascontiguousarray(a)
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())
    return h.hexdigest()


def read_model_bytes(path) -> tuple[bytes, bytes]:
    """The bytes of a model file and of its JSON record, each read once.

    A caller that hashes these bytes and loads the model from them
    (:meth:`LearnedMap.from_bytes`) uses exactly the content it hashed, even if the files
    are replaced meanwhile.

    Raises
    ------
    ValueError
        A name not ending in ``.joblib``, a missing or unreadable file (the message names it).
    """
    path = _model_path(path)
    sidecar = path.with_suffix(".json")
    out = []
    for p in (path, sidecar):
        try:
            out.append(p.read_bytes())
        except FileNotFoundError:
            raise ValueError(
                f"learned model {path} needs both {path.name} and {sidecar.name}; {p} is missing"
            ) from None
        except OSError as exc:
            raise ValueError(f"cannot read {p} ({exc.strerror or exc})") from None
    return out[0], out[1]


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
class LearnedMap(ModelRecord):
    """Trained importance models, one per density, and their record (:class:`ModelRecord`).

    Attributes
    ----------
    models : dict of float -> HistGradientBoostingRegressor
        Density k / N -> regressor of the centred log error on :data:`FEATURE_NAMES`.
    meta : dict
        The JSON record.
    """

    FORMAT: ClassVar[str] = FORMAT
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
        threads = int(self.meta.get("options", {}).get("threads", 1))
        y = predict_rows(self.model_for(density), x.reshape(-1, x.shape[-1]), threads=threads)
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

    def _payload(self) -> dict:
        return {"models": {repr(d): m for d, m in self.models.items()}}

    @classmethod
    def load(cls, path) -> LearnedMap:
        """Load a model saved by :meth:`save`, after checking its record.

        Refuses (``ValueError``) a missing sidecar, another format or feature-set version,
        another scikit-learn version (pickles do not carry across versions) and a joblib file
        whose SHA-256 differs from the sidecar's, all before unpickling. Unpickling runs code:
        load only your own results. Each file is read once (:meth:`from_bytes`).
        """
        path = _model_path(path)
        data, record = read_model_bytes(path)
        return cls.from_bytes(data, record, path=path)

    @classmethod
    def from_bytes(cls, data: bytes, record: bytes, *, path) -> LearnedMap:
        """A model from the bytes of its joblib file and of its JSON record.

        The record is checked first (JSON, format, feature set, scikit-learn version, the
        densities it lists) and the SHA-256 of ``data`` must equal the record's
        ``model_sha256``: only then are the bytes unpickled, and the unpickled payload must
        hold one regressor of the feature set per density the record lists.

        Parameters
        ----------
        data, record : bytes
            The ``.joblib`` file's and the ``.json`` record's contents.
        path : str or Path
            The model file's name, for messages.

        Raises
        ------
        ValueError
            One line naming the file and what is wrong with it.
        """
        path = Path(path)
        sidecar = path.with_suffix(".json")
        meta = _parse_record(record, sidecar)
        _check_meta(meta, path, hashlib.sha256(data).hexdigest())
        try:
            payload = joblib.load(io.BytesIO(data))
        except (
            Exception
        ) as exc:  # the hash matched: not a pickle (a renamed text file), or another library
            msg = " ".join(str(exc).split())
            raise ValueError(
                f"{path}: cannot unpickle the model ({type(exc).__name__}: {msg})"
            ) from None
        models = _payload_models(payload, path)
        if sorted(models) != sorted(float(d) for d in meta["densities"]):
            raise ValueError(
                f"{path}: densities {sorted(models)} differ from its record's "
                f"{sorted(meta['densities'])}"
            )
        return cls._loaded(models, meta)


def _parse_record(record: bytes, sidecar: Path) -> dict:
    """The JSON record of a model as a dict whose ``densities`` are distinct numbers in (0, 1]."""
    try:
        meta = json.loads(record.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise ValueError(
            f"{sidecar}: not a JSON model record ({' '.join(str(exc).split())})"
        ) from None
    if not isinstance(meta, dict):
        raise ValueError(f"{sidecar}: not a model record (a JSON {type(meta).__name__})")
    dens = meta.get("densities")
    ok = isinstance(dens, list) and len(dens) > 0
    ok = ok and all(
        isinstance(d, (int, float)) and not isinstance(d, bool) and math.isfinite(d) and 0 < d <= 1
        for d in dens
    )
    if not ok or len(set(dens)) != len(dens):
        raise ValueError(
            f"{sidecar}: 'densities' must list distinct sample fractions in (0, 1], got {dens!r}"
        )
    return meta


def _payload_models(payload, path: Path) -> dict:
    """density -> regressor of an unpickled payload, each predicting from the feature set."""
    models = payload.get("models") if isinstance(payload, dict) else None
    if not isinstance(models, dict) or payload.get("format") != FORMAT or not models:
        raise ValueError(f"{path}: not a {FORMAT} model file (unexpected content)")
    out = {}
    for d, m in models.items():
        try:
            dens = float(d)
        except (TypeError, ValueError):
            raise ValueError(f"{path}: density key {d!r} is not a number") from None
        n_in = getattr(m, "n_features_in_", None)
        if not callable(getattr(m, "predict", None)) or n_in != len(FEATURE_NAMES):
            raise ValueError(
                f"{path}: the model for density {d} is not a regressor of the "
                f"{len(FEATURE_NAMES)} features of this feature set"
            )
        out[dens] = m
    return out


def _check_meta(meta: dict, path: Path, digest: str) -> None:
    """Refuse a record of another format, feature set or library version, or another file
    (``digest``: the SHA-256 of the model bytes about to be unpickled)."""
    if meta.get("format") != FORMAT:
        raise ValueError(f"{path}: not a {FORMAT} model (format {meta.get('format')!r})")
    if meta.get("feature_set_version") != FEATURE_SET_VERSION or meta.get("feature_names") != list(
        FEATURE_NAMES
    ):
        raise ValueError(
            f"{path}: trained on feature set version {meta.get('feature_set_version')!r}, this "
            f"simlunar computes version {FEATURE_SET_VERSION}: retrain the model"
        )
    check_record_matches(meta, path, digest)


_CACHE: dict[tuple, LearnedMap] = {}
#: resolved model path -> (SHA-256 of its bytes, model, holders): models a work unit read,
#: verified and pinned for its duration (:func:`pinned_models`); module-level so that forked
#: workers of the unit see them too
_PINNED: dict[str, tuple[str, LearnedMap, int]] = {}
_PIN_LOCK = threading.Lock()


@contextlib.contextmanager
def pinned_models(models: Mapping[str | Path, tuple[str, LearnedMap]]) -> Iterator[None]:
    """While inside, :func:`learned` uses these models for these paths and never reads the
    files again: a file replaced during a run cannot reach a unit that hashed the old one.

    Parameters
    ----------
    models : mapping of path -> (sha256 hex, LearnedMap)
        Each model as loaded from the bytes whose hash is given.

    Raises
    ------
    ValueError
        A path already pinned (by a concurrent unit) with other content.
    """
    keys = []
    try:
        with _PIN_LOCK:
            for p, (digest, m) in models.items():
                key = str(Path(p).resolve())
                held = _PINNED.get(key)
                if held is not None and held[0] != digest:
                    raise ValueError(
                        f"{p}: another unit of this run read other content for this model file "
                        "(the file changed during the run)"
                    )
                _PINNED[key] = (digest, m if held is None else held[1], (held or (0, 0, 0))[2] + 1)
                keys.append(key)
        yield
    finally:
        with _PIN_LOCK:
            for key in keys:
                digest, m, n = _PINNED[key]
                if n <= 1:
                    del _PINNED[key]
                else:
                    _PINNED[key] = (digest, m, n - 1)


def learned(image, *, model, density: float) -> np.ndarray:
    """The ``learned`` feature map: :meth:`LearnedMap.predict` of the model file ``model``.

    A model pinned by :func:`pinned_models` (a work unit's, hashed into its cache key) is
    used as pinned; others are loaded (each file read once) and cached by (resolved path,
    size, modification time).

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
    pinned = _PINNED.get(str(path))
    if pinned is not None:
        return pinned[1].predict(image, density=density)
    try:
        st = path.stat()
    except OSError:
        raise ValueError(f"learned model file not found: {model}") from None
    key = (str(path), st.st_size, st.st_mtime_ns)
    if key not in _CACHE:
        _CACHE.clear()
        _CACHE[key] = LearnedMap.load(path)
    return _CACHE[key].predict(image, density=density)
