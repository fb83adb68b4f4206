"""Atomic model file + JSON record saving (simlunar.features.model_save)."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from typing import ClassVar

import joblib
import pytest

from simlunar.features import learned
from simlunar.features.model_save import ModelRecord, check_record_matches, save_with_record


def test_save_with_record_writes_the_hash_and_leaves_meta_alone(tmp_path):
    meta = {"format": "x", "densities": [0.01]}
    path, sidecar = save_with_record(tmp_path / "sub" / "m.joblib", {"a": [1, 2]}, meta)
    assert meta == {"format": "x", "densities": [0.01]}
    assert sidecar == path.with_suffix(".json") and path.parent.name == "sub"
    record = json.loads(sidecar.read_text())
    assert record["model_file"] == "m.joblib"
    assert record["model_sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    assert joblib.load(path) == {"a": [1, 2]}


def test_a_resave_replaces_both_and_leaves_no_temporary_files(tmp_path):
    save_with_record(tmp_path / "m.joblib", {"v": 1}, {"format": "x"})
    path, sidecar = save_with_record(tmp_path / "m.joblib", {"v": 2}, {"format": "y"})
    assert joblib.load(path) == {"v": 2} and json.loads(sidecar.read_text())["format"] == "y"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.joblib", "m.json"]


def test_an_unwritable_target_names_the_file(tmp_path):
    (tmp_path / "m.json").mkdir()
    (tmp_path / "m.json" / "x").write_text("keeps the folder non-empty")
    with pytest.raises(OSError):
        save_with_record(tmp_path / "m.joblib", {"v": 1}, {})
    assert not [p for p in tmp_path.iterdir() if p.suffix == ".tmp"]


def test_learned_re_exports_save_with_record():
    assert learned.save_with_record is save_with_record


@dataclass(frozen=True, eq=False)
class _Box(ModelRecord):
    FORMAT: ClassVar[str] = "box/1"
    model: object
    meta: dict = field(default_factory=dict)

    def _payload(self) -> dict:
        return {"model": self.model}


def test_a_model_record_saves_its_format_and_payload_and_loads_without_the_file_name(tmp_path):
    box = _Box([3, 4], {"format": "box/1", "options": {"threads": 2}})
    assert box.model_sha256 == ""
    path, sidecar = box.save(tmp_path / "b.joblib")
    # the container is not pickled: only the format tag and the payload
    assert joblib.load(path) == {"format": "box/1", "model": [3, 4]}
    record = json.loads(sidecar.read_text())
    back = _Box._loaded(joblib.load(path)["model"], record)
    assert back.model == [3, 4] and "model_file" not in back.meta
    assert back.model_sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert back.meta["options"] == {"threads": 2} and box.meta == {
        "format": "box/1",
        "options": {"threads": 2},
    }


def test_a_record_of_another_scikit_learn_is_refused_naming_the_file_and_both_versions():
    import sklearn

    check_record_matches(
        {"versions": {"scikit-learn": sklearn.__version__}, "model_sha256": "ab"}, "m.joblib", "ab"
    )
    for meta, saved in (({"versions": {"scikit-learn": "0.1"}}, "0.1"), ({}, "None")):
        want = rf"^m\.joblib: saved with scikit-learn {saved}, installed {sklearn.__version__}: "
        with pytest.raises(ValueError, match=want):
            check_record_matches(meta, "m.joblib", "ab")


def test_a_model_whose_bytes_are_not_those_recorded_is_refused():
    import sklearn

    meta = {"versions": {"scikit-learn": sklearn.__version__}, "model_sha256": "ab"}
    with pytest.raises(ValueError, match=r"^m\.joblib: SHA-256 does not match its record"):
        check_record_matches(meta, "m.joblib", "cd")
