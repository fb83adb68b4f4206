"""Atomic saving of a model file (joblib) with its JSON record (name and SHA-256), the pair a
load checks before unpickling (split from :mod:`simlunar.features.learned`, which re-exports
:func:`save_with_record`), and :class:`ModelRecord`, what the trained-model containers (the
learned map's and the learned reconstruction's) share."""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import tempfile
from pathlib import Path
from typing import ClassVar

import joblib

from simlunar.features._stack import _model_path

__all__ = ["ModelRecord", "check_record_matches", "save_with_record"]


def save_with_record(path, payload, meta: dict) -> tuple[Path, Path]:
    """Write ``payload`` with joblib to ``path`` and ``meta`` beside it as JSON (``.json``),
    with the model file's name and SHA-256 added: the record a load checks before unpickling.

    Atomic: both files are written beside their targets and fsynced before either is renamed
    (:func:`_write_pair`), so a failed save leaves the old model and record untouched and its
    error names the file.

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
    buf = io.BytesIO()
    joblib.dump(payload, buf)
    data = buf.getvalue()
    meta = {**meta, "model_file": path.name, "model_sha256": hashlib.sha256(data).hexdigest()}
    record = (json.dumps(meta, indent=2, sort_keys=True) + "\n").encode()
    sidecar = path.with_suffix(".json")
    _write_pair(((path, data), (sidecar, record)))
    return path, sidecar


def check_record_matches(meta: dict, path, digest: str) -> None:
    """Refuse a model whose record says it was saved with another scikit-learn than the
    installed one (pickled regressors do not carry across versions), or whose recorded SHA-256
    is not ``digest`` (that of the bytes about to be unpickled: a file truncated, modified or
    replaced since it was saved): a one-line ``ValueError`` naming ``path``."""
    import sklearn  # only when a model is loaded: importing the features stays light

    saved = meta.get("versions", {}).get("scikit-learn")
    if saved != sklearn.__version__:
        raise ValueError(
            f"{path}: saved with scikit-learn {saved}, installed {sklearn.__version__}: retrain"
        )
    if digest != meta.get("model_sha256"):
        raise ValueError(
            f"{path}: SHA-256 does not match its record (truncated, modified or replaced)"
        )


def _write_pair(files) -> None:
    """Write each ``(path, bytes)`` beside its target and fsync it; only when every one is
    written are they renamed over their targets, so a failed save (a full disk, a read-only
    folder) leaves the old model and record untouched. ``OSError`` names the target file."""
    done: list[tuple[str, Path]] = []
    try:
        for target, data in files:
            try:
                fd, tmp = tempfile.mkstemp(
                    prefix=f".{target.name}.", suffix=".tmp", dir=target.parent
                )
                done.append((tmp, target))
                with os.fdopen(fd, "wb") as f:
                    f.write(data)
                    f.flush()
                    os.fsync(f.fileno())
                os.chmod(tmp, 0o644)
            except OSError as exc:
                raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from None
        # the model before its record: a reader between the two renames finds the new model
        # beside the old record and refuses it (hash), never a mismatched pair in use
        for tmp, target in done:
            os.replace(tmp, target)
        done.clear()
    finally:
        for tmp, _ in done:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


class ModelRecord:
    """Base of a trained-model container: a frozen dataclass with the model(s) first and
    ``meta``, the model's JSON record (format, feature set, densities, options, input hashes,
    library versions, provenance), second.

    A subclass sets :attr:`FORMAT` and :meth:`_payload`. The saved file pickles the payload
    (a dict of the format and the regressors), never the container, so a file stays loadable
    whatever module the container lives in.
    """

    #: the format tag of the payload and of the record
    FORMAT: ClassVar[str]
    meta: dict

    def _payload(self) -> dict:
        """What is pickled beside the format tag (e.g. ``{"model": regressor}``)."""
        raise NotImplementedError

    def save(self, path) -> tuple[Path, Path]:
        """Write ``path`` (joblib of the format and :meth:`_payload`) and its JSON record
        (``.json``), with :func:`save_with_record`.

        Parameters
        ----------
        path : str or Path
            Ends in ``.joblib``; parent folders are created.

        Returns
        -------
        (Path, Path)
            The joblib file and its record.
        """
        return save_with_record(path, {"format": self.FORMAT, **self._payload()}, self.meta)

    @property
    def model_sha256(self) -> str:
        """SHA-256 (hex) of the model file the record names ("" for a model never saved)."""
        return str(self.meta.get("model_sha256", ""))

    @classmethod
    def _loaded(cls, models, meta: dict):
        """The container of unpickled ``models`` and their checked record, less the record's
        ``model_file`` (the name the file was saved under; it may have been moved since)."""
        return cls(models, {k: v for k, v in meta.items() if k != "model_file"})
