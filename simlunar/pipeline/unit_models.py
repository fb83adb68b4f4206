"""The trained models a work unit reads, loaded from the bytes its cache key hashed, and the
check that every other input file still holds those bytes when the unit is stored."""

from __future__ import annotations

import contextlib
import hashlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import simlunar.features.learned
import simlunar.reconstruction.learned  # noqa: F401  (registers its container)
from simlunar.errors import ConfigError, InputChangedError
from simlunar.features.model_save import ModelRecord
from simlunar.pipeline.inputs import model_inputs

__all__ = ["MAX_RECORD_BYTES", "model_class", "read_unit_models", "verify_inputs"]

#: Largest JSON record of a model file read: records `simlunar train` writes are a few kB
#: (options, densities, feature names, input hashes); a larger one is no record of it
MAX_RECORD_BYTES = 16_000_000


def _changed(key: str, path, digest: str, expected: str) -> InputChangedError:
    return InputChangedError(
        f"{key}: {path} changed during the run (sha256 {digest[:12]}, the run hashed "
        f"{expected[:12]} into the unit's cache key); nothing of this unit is stored"
    )


def _bytes_sha256(path: Path, key: str) -> tuple[bytes, str]:
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise InputChangedError(
            f"{key}: cannot read {path} during the run ({exc.strerror or exc})"
        ) from None
    return data, hashlib.sha256(data).hexdigest()


def read_unit_models(
    inputs: dict[str, dict[str, str]], config: Mapping[str, Any]
) -> dict[str, tuple[str, Any]]:
    """The trained models a unit reads (every option of ``config`` declared a ``model`` file,
    :func:`model_inputs`), each loaded from the bytes whose SHA-256 its cache key holds
    (``inputs``: :func:`input_hashes` of the unit, as the run computed them).

    Each model file and its record are read once; their hashes must equal the run's, so the
    model a unit uses is the content its key names, whatever happens to the files later
    (:func:`simlunar.features.learned.pinned_models` then keeps the unit from reading a learned
    map again). The loader is the model container whose record format the option declares
    (:class:`~simlunar.features.model_save.ModelRecord`): a model of another kind (a map's
    model named as a reconstruction's) is refused.

    Returns
    -------
    dict
        model path -> (SHA-256 hex of the model bytes, the loaded container)

    Raises
    ------
    InputChangedError
        A model file or its record differs from the run's hash of it (one line naming it).
    ConfigError
        A model the loader refuses (one line naming the key and the file).
    """
    out: dict[str, tuple[str, Any]] = {}
    for key, marker in model_inputs(config).items():
        v = inputs.get(key)
        if v is None:
            continue
        path = Path(v["path"])
        data, digest = _bytes_sha256(path, key)
        if digest != v["sha256"]:
            raise _changed(key, path, digest, v["sha256"])
        rec = inputs.get(f"{key}.json")
        sidecar = path.with_suffix(".json")
        with contextlib.suppress(OSError):  # an unreadable record is reported just below
            if sidecar.stat().st_size > MAX_RECORD_BYTES:
                raise ConfigError(
                    f"{key}.json: {sidecar} holds {sidecar.stat().st_size / 1e6:.3g} MB; a "
                    f"model's record is a few kB (at most {MAX_RECORD_BYTES / 1e6:g} MB): not "
                    "the record `simlunar train` wrote"
                )
        record, rdigest = _bytes_sha256(sidecar, f"{key}.json")
        if rec is not None and rdigest != rec["sha256"]:
            raise _changed(f"{key}.json", path.with_suffix(".json"), rdigest, rec["sha256"])
        try:
            model = model_class(marker.format).from_bytes(data, record, path=path)
        except ValueError as exc:
            raise ConfigError(f"{key}: {' '.join(str(exc).split())}") from None
        out[str(path)] = (digest, model)
    return out


def model_class(fmt: str | None):
    """The model container (a :class:`~simlunar.features.model_save.ModelRecord` subclass)
    whose record format is ``fmt``: every trained model simlunar loads."""
    for cls in ModelRecord.__subclasses__():
        if getattr(cls, "FORMAT", None) == fmt:
            return cls
    raise TypeError(f"no model container reads the record format {fmt!r}")


def verify_inputs(inputs: dict[str, dict[str, str]], *, skip=()) -> None:
    """Refuse, in one line, an input file whose bytes are no longer those the run hashed
    into the unit's cache key (``inputs``: :func:`input_hashes`); ``skip``: key paths not
    checked (the models a unit loaded from verified bytes)."""
    for key, v in inputs.items():
        if key in skip:
            continue
        _, digest = _bytes_sha256(Path(v["path"]), key)
        if digest != v["sha256"]:
            raise _changed(key, v["path"], digest, v["sha256"])
