"""The models a unit reads and the inputs it verifies (simlunar/pipeline/unit_models.py): each
loaded from the bytes the run hashed, every change since refused in one line."""

from __future__ import annotations

import hashlib

import pytest

from simlunar.errors import ConfigError, InputChangedError
from simlunar.pipeline.unit_models import read_unit_models, verify_inputs
from simlunar.results.store import file_sha256


def test_verify_inputs_by_hand(tmp_path):
    f = tmp_path / "a.bin"
    f.write_bytes(b"one")
    inputs = {"terrain.file": {"path": str(f), "sha256": hashlib.sha256(b"one").hexdigest()}}
    verify_inputs(inputs)  # unchanged: nothing to say
    f.write_bytes(b"two")
    # the message names the key, the file and both hashes' first 12 hex digits
    new, old = hashlib.sha256(b"two").hexdigest()[:12], hashlib.sha256(b"one").hexdigest()[:12]
    with pytest.raises(
        InputChangedError,
        match=rf"^terrain.file: {f} changed during the run \(sha256 {new}, the run hashed {old} ",
    ):
        verify_inputs(inputs)
    verify_inputs(inputs, skip=("terrain.file",))  # skipped keys are not read
    f.unlink()
    with pytest.raises(InputChangedError, match=rf"terrain.file: cannot read {f} during the run"):
        verify_inputs(inputs)


def test_read_unit_models_checks_hashes_before_loading(tmp_path):
    # no training needed: every refusal here happens before or in the loader's record check
    model, record = tmp_path / "m.joblib", tmp_path / "m.json"
    model.write_bytes(b"not a pickle")
    record.write_text("{}")
    key = "study.strategy_options.l.feature_opts.model"

    def entry(p):
        return {"path": str(p), "sha256": file_sha256(p)}

    inputs = {key: entry(model), f"{key}.json": entry(record), "terrain.file": entry(record)}
    config = {"study": {"strategy_options": {"l": {"feature_opts": {"model": str(model)}}}}}
    # hashes match: the loader refuses the record, in one line naming the key
    with pytest.raises(ConfigError, match=rf"^{key}: ") as err:
        read_unit_models(inputs, config)
    assert "\n" not in str(err.value)
    record.write_text('{"format": 1}')  # the record changed since the run hashed it
    with pytest.raises(InputChangedError, match=rf"^{key}.json: {record} changed during the run"):
        read_unit_models(inputs, config)
    model.write_bytes(b"another model")
    with pytest.raises(InputChangedError, match=rf"^{key}: {model} changed during the run"):
        read_unit_models(inputs, config)
    # units without a model read none
    assert read_unit_models({"terrain.file": entry(record)}, {"terrain": {"file": "x"}}) == {}
