"""`simlunar run` with a bad learned-reconstruction model file (or a learned map's model that is
no pickle): every case is refused before any render in one line naming the key and the file,
exit 2, nothing written (no ``config.yaml`` left behind), and no unverified byte unpickled.

Each case breaks one check of :func:`simlunar.pipeline.unit_models.read_unit_models` (presence,
size, version, record, hash, payload); the good model passes them all."""

from __future__ import annotations

import functools
import hashlib
import json
import pickle
import tempfile
from pathlib import Path

import numpy as np
import pytest

from tests.pipeline.test_bad_inputs import (
    LEARNED,
    MODEL,
    Case,
    _Boom,
    _model_bytes,
    _run_case,
    _set,
    with_,
)

RMODEL = "models/r.joblib"
RECON = with_("study.reconstructions", ["linear", {"learned": {"model": RMODEL}}])
LABELLED = with_(
    "study.reconstructions", ["linear", {"mine": {"reconstruction": "learned", "model": RMODEL}}]
)
KEY = "study.reconstructions.learned.model: "


@functools.lru_cache(maxsize=1)
def _recon_bytes() -> tuple[bytes, dict]:
    """A real tiny learned-reconstruction model: its joblib bytes and its record."""
    from scipy import ndimage

    from simlunar.features.learned import LearnedOptions
    from simlunar.planner.learning import train_learned_reconstruction

    def pair(seed):
        r = np.random.default_rng(seed)
        d = ndimage.gaussian_filter(r.standard_normal((32, 40)), 1.5)
        z = ndimage.gaussian_filter(r.standard_normal((32, 40)), 8) * 20 + d / d.std()
        return np.clip(0.5 + 0.15 * d / d.std(), 0.01, None), z

    m = train_learned_reconstruction(
        [pair(0), pair(1)],
        densities=(1 / 16,),
        options=LearnedOptions(layouts=1, pixels_per_example=400, max_iter=5),
        rng=0,
    )
    with tempfile.TemporaryDirectory() as tmp:
        path, record = m.save(Path(tmp) / "r.joblib")
        return path.read_bytes(), json.loads(record.read_text())


def recon_files(data=None, *, edit=None, rehash=False, raw_record=None, record=True, good=None):
    """A setup writing ``models/r.joblib`` (``data``: bytes or a callable of the good bytes)
    and ``models/r.json`` (the good record, ``edit``-ed, or ``raw_record``); ``rehash``: the
    record's hash made to match the written bytes (a forged but consistent record); ``good``:
    where the good pair comes from (default the learned reconstruction's)."""

    def setup(d: Path) -> None:
        body0, meta = (good or _recon_bytes)()
        body = body0 if data is None else (data(body0) if callable(data) else data)
        meta = dict(meta)
        if edit is not None:
            edit(meta)
        if rehash:
            meta["model_sha256"] = hashlib.sha256(body).hexdigest()
        (d / "models").mkdir(exist_ok=True)
        (d / RMODEL).write_bytes(body)
        rec = d / "models" / "r.json"
        if raw_record is not None:
            rec.write_bytes(raw_record if isinstance(raw_record, bytes) else raw_record.encode())
        elif record:
            rec.write_text(json.dumps(meta))

    return setup


def _map_text_with_true_hash(d: Path) -> None:
    """A learned map's model: a text file renamed ``.joblib`` whose record carries its true
    SHA-256 (the hash check passes; the unpickling must be refused in one line)."""
    _, meta = _model_bytes()
    body = b"name: not a model\n"
    meta = {**meta, "model_sha256": hashlib.sha256(body).hexdigest()}
    (d / "models").mkdir(exist_ok=True)
    (d / MODEL).write_bytes(body)
    (d / "models" / "m.json").write_text(json.dumps(meta))


CASES = [
    Case("recon model absent", RECON, KEY + "cannot read models/r.joblib (No such file or directory) (a learned model: make it with `simlunar train"),
    Case("recon model absent under a label", LABELLED, "study.reconstructions.mine.model: cannot read models/r.joblib"),
    Case("recon record missing", RECON, "study.reconstructions.learned.model.json: cannot read models/r.json", setup=recon_files(record=False)),
    Case("recon model truncated", RECON, KEY + "models/r.joblib: SHA-256 does not match its record", setup=recon_files(lambda b: b[: len(b) // 2])),
    Case("recon model empty", RECON, KEY + "models/r.joblib: SHA-256 does not match its record", setup=recon_files(b"")),
    Case("recon model a hostile pickle, forged hash", RECON, "SHA-256 does not match its record", setup=recon_files(lambda b: pickle.dumps(_Boom()), edit=_set("model_sha256", "0" * 64))),
    Case("recon model other scikit-learn", RECON, KEY + "models/r.joblib: saved with scikit-learn 0.1, installed", setup=recon_files(edit=_set("versions.scikit-learn", "0.1"))),
    Case("recon record not JSON", RECON, KEY + "models/r.json: not a readable JSON record", setup=recon_files(raw_record="{format: [")),
    Case("recon record empty", RECON, "models/r.json: not a readable JSON record", setup=recon_files(raw_record="")),
    Case("recon record binary", RECON, "models/r.json: not a readable JSON record", setup=recon_files(raw_record=b"\xff\xfe{\x00")),
    Case("recon record of 20 MB", RECON, "study.reconstructions.learned.model.json: models/r.json holds 20 MB; a model's record is a few kB", setup=recon_files(raw_record=b" " * 20_000_000)),
    Case("map record of 20 MB", LEARNED, "study.strategy_options.l.feature_opts.model.json: models/m.json holds 20 MB", setup=lambda d: ((d / "models").mkdir(), (d / MODEL).write_bytes(_model_bytes()[0]), (d / "models" / "m.json").write_bytes(b"{" + b" " * 20_000_000 + b"}"))),
    Case("recon record a JSON list", RECON, "not a simlunar-learned-reconstruction/1 model (format None)", setup=recon_files(raw_record="[1, 2]")),
    Case("recon record other feature set", RECON, "trained on another feature set", setup=recon_files(edit=_set("recon_feature_version", 0))),
    Case("recon model a renamed text file, true hash", RECON, KEY + "models/r.joblib: cannot be read back", setup=recon_files(b"name: not a model\n", rehash=True)),
    Case("recon model consistent record, foreign payload", RECON, "not a simlunar-learned-reconstruction/1 model file", setup=recon_files(lambda b: pickle.dumps({"models": [1]}), rehash=True)),
    Case("recon model consistent record, no regressor", RECON, "its payload holds no regressor", setup=recon_files(lambda b: pickle.dumps({"format": "simlunar-learned-reconstruction/1", "model": "x"}), rehash=True)),
    Case("recon model is a learned map's", RECON, "not a simlunar-learned-reconstruction/1 model (format 'simlunar-learned-map/1')", setup=recon_files(good=_model_bytes)),
    Case("map model a renamed text file, true hash", LEARNED, "study.strategy_options.l.feature_opts.model: models/m.joblib: cannot unpickle the model (", setup=_map_text_with_true_hash),
]  # fmt: skip


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_bad_model_file_exits_2_with_one_line_and_writes_nothing(case, tmp_path, monkeypatch):
    _run_case(case, tmp_path, monkeypatch)
    assert not (tmp_path / "case" / "UNPICKLED").exists()


def test_the_good_reconstruction_model_passes_the_checks(tmp_path, monkeypatch):
    """The cases above differ from a model that loads: each fails for its own reason."""
    from simlunar.config.loading import validate_data
    from simlunar.pipeline.preflight import check_units
    from simlunar.pipeline.runner import expand

    recon_files()(tmp_path)
    monkeypatch.chdir(tmp_path)
    for data in (RECON, LABELLED):
        check_units(expand(validate_data(data)))
