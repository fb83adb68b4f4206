"""Learned importance map: features, target, a planted relationship on held-out data, model files."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import ndimage
from scipy.stats import rankdata

from simlunar.features import feature_map
from simlunar.features._stack import FEATURE_NAMES, image_features
from simlunar.features.learned import LearnedMap, LearnedOptions, pitch_of
from simlunar.planner import plan
from simlunar.planner.learning import error_target, train_learned_map

DENSITY = 1 / 32
#: held-out rank correlation the learned map must reach on every test terrain; measured 0.63-0.81
#: on seeds 100-105 (the image's 5 px standard deviation alone: 0.34-0.54, the wavelet energy
#: 0.50-0.71); a constant map gives 0
MIN_SPEARMAN = 0.45


def planted_pair(seed: int, shape=(96, 128)):
    """A terrain whose reconstruction error lies where the image shows high-contrast texture.

    A smooth surface plus rough discs; the image is flat grey with faint shading, and inside
    the discs an albedo texture independent of the relief (the image says where, not what).
    """
    r = np.random.default_rng(seed)
    y, x = np.mgrid[0 : shape[0], 0 : shape[1]]
    mask = np.zeros(shape)
    for _ in range(3):
        cy, cx, rad = r.uniform(0, shape[0]), r.uniform(0, shape[1]), r.uniform(8, 18)
        mask = np.maximum(mask, ((y - cy) ** 2 + (x - cx) ** 2 < rad**2).astype(float))
    mask = ndimage.gaussian_filter(mask, 1.0)
    base = ndimage.gaussian_filter(r.standard_normal(shape), 16) * 20
    truth = base + 2 * mask * ndimage.gaussian_filter(r.standard_normal(shape), 1.0)
    texture = ndimage.gaussian_filter(r.standard_normal(shape), 0.8)
    shading = 0.05 * ndimage.gaussian_filter(r.standard_normal(shape), 8)
    return np.clip(0.5 + shading + 0.3 * mask * texture, 0.01, None), truth


def spearman(a, b) -> float:
    """Rank correlation; 0 for a constant input (no ordering, so no information)."""
    ra, rb = rankdata(np.ravel(a)), rankdata(np.ravel(b))
    if ra.std() == 0 or rb.std() == 0:
        return 0.0
    return float(np.corrcoef(ra, rb)[0, 1])


def recovers(predict, pairs) -> bool:
    """The acceptance criterion: held-out Spearman >= MIN_SPEARMAN on every pair."""
    return all(
        spearman(predict(img), error_target(z, density=DENSITY, rng=1)) >= MIN_SPEARMAN
        for img, z in pairs
    )


FAST = LearnedOptions(pixels_per_example=3000, max_iter=40)


@pytest.fixture(scope="module")
def model():
    train = [planted_pair(s) for s in range(4)]
    return train_learned_map(train, densities=[DENSITY, 1 / 8], options=FAST, rng=0)


@pytest.fixture(scope="module")
def held_out():
    return [planted_pair(s) for s in range(100, 103)]


def test_feature_stack_shape_and_names():
    img = np.random.default_rng(0).random((40, 50))
    f = image_features(img, pitch=5.0)
    assert f.shape == (40, 50, len(FEATURE_NAMES)) and f.dtype == np.float32
    assert 38 <= len(FEATURE_NAMES) <= 45 and len(set(FEATURE_NAMES)) == len(FEATURE_NAMES)
    assert np.all(np.isfinite(f))
    with pytest.raises(ValueError, match="pitch"):
        image_features(img, pitch=0.5)


def test_features_ignore_exposure():
    # the image is divided by its mean and the shadow level is relative: a brighter exposure of
    # the same scene gives the same features
    img = 0.01 + np.random.default_rng(1).random((32, 48, 3))
    np.testing.assert_allclose(
        image_features(4 * img, pitch=4.0), image_features(img, pitch=4.0), rtol=1e-4, atol=1e-4
    )


def test_learned_map_recovers_planted_relationship_on_held_out_data(model, held_out):
    assert recovers(lambda img: model.predict(img, density=DENSITY), held_out)
    # importance maps are positive and relative
    m = model.predict(held_out[0][0], density=DENSITY)
    assert m.shape == held_out[0][0].shape and np.all(m > 0) and m.max() == 1.0


def test_criterion_fails_a_constant_map(held_out):
    assert not recovers(lambda img: np.ones(img.shape), held_out)


def test_untrained_density_uses_nearest_model(model):
    assert model.model_for(1 / 40) is model.models[DENSITY]
    assert model.model_for(1 / 10) is model.models[1 / 8]
    assert model.densities == [DENSITY, 1 / 8]


def test_save_load_round_trip(model, held_out, tmp_path):
    path, sidecar = model.save(tmp_path / "sub" / "m.joblib")
    assert sidecar == tmp_path / "sub" / "m.json"
    meta = json.loads(sidecar.read_text())
    assert meta["feature_names"] == list(FEATURE_NAMES) and meta["examples"] == 4
    assert meta["options"]["max_iter"] == 40 and len(meta["input_sha256"]) == 4
    assert {"scikit-learn", "numpy", "simlunar"} <= set(meta["versions"])
    loaded = LearnedMap.load(path)
    img = held_out[0][0]
    np.testing.assert_array_equal(
        loaded.predict(img, density=DENSITY), model.predict(img, density=DENSITY)
    )


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        ("tamper", "SHA-256"),
        ("feature_version", "feature set version"),
        ("sklearn_version", "scikit-learn"),
        ("format", "not a"),
        ("no_sidecar", "needs both"),
    ],
)
def test_load_refuses_mismatched_files(model, tmp_path, edit, match):
    path, sidecar = model.save(tmp_path / "m.joblib")
    meta = json.loads(sidecar.read_text())
    if edit == "tamper":
        data = bytearray(path.read_bytes())
        data[len(data) // 2] ^= 0xFF
        path.write_bytes(bytes(data))
    elif edit == "no_sidecar":
        sidecar.unlink()
    else:
        key, value = {
            "feature_version": ("feature_set_version", 999),
            "format": ("format", "other/1"),
            "sklearn_version": ("versions", {**meta["versions"], "scikit-learn": "0.1"}),
        }[edit]
        sidecar.write_text(json.dumps({**meta, key: value}))
    with pytest.raises(ValueError, match=match):
        LearnedMap.load(path)


def test_model_file_must_be_joblib(model, tmp_path):
    with pytest.raises(ValueError, match=r"\.joblib"):
        model.save(tmp_path / "m.pkl")


def test_registered_feature_and_strategy(model, held_out, tmp_path):
    path, _ = model.save(tmp_path / "m.joblib")
    img = held_out[1][0]
    m = feature_map("learned", img, model=str(path), density=DENSITY)
    np.testing.assert_array_equal(m, model.predict(img, density=DENSITY))
    k = round(DENSITY * img.size)
    opts = {"feature_opts": {"model": path, "density": DENSITY}, "placement": "lloyd"}
    p = plan("learned", k, image=img, rng=0, **opts)
    assert p.k == k
    with pytest.raises(ValueError, match="needs option"):
        feature_map("learned", img)
    with pytest.raises(ValueError, match="not found"):
        feature_map("learned", img, model=tmp_path / "none.joblib", density=DENSITY)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"layouts": 0}, "layouts must be >= 1, got 0"),
        ({"pixels_per_example": 5}, "pixels_per_example must be >= 100, got 5"),
        ({"max_iter": 1.5}, "max_iter must be an integer, got 1.5"),
        ({"max_leaf_nodes": True}, "max_leaf_nodes must be a finite number, got True"),
        ({"learning_rate": 0}, "learning_rate must be > 0, got 0"),
        ({"l2_regularization": -1}, "l2_regularization must be >= 0, got -1"),
        ({"threads": 0}, "threads must be >= 1, got 0"),
    ],
)
def test_options_are_validated(kwargs, match):
    with pytest.raises(ValueError, match=match):
        LearnedOptions(**kwargs)


def test_training_inputs_are_validated():
    img, z = planted_pair(0, shape=(24, 24))
    with pytest.raises(ValueError, match="truth"):
        train_learned_map([(img, z[:, :10])], densities=[0.1], rng=0)
    with pytest.raises(ValueError, match="distinct"):
        train_learned_map([(img, z)], densities=[0.1, 0.1], rng=0)
    with pytest.raises(ValueError, match="density"):
        pitch_of(0.0)
    with pytest.raises(ValueError, match="at least one"):
        train_learned_map([], densities=[0.1], rng=0)


def test_a_failed_save_leaves_the_old_model_and_record_untouched(model, tmp_path, monkeypatch):
    """The disk fills while the record is written: neither file changes, no temporary file
    is left, and the error names the record."""
    import errno
    import os

    path, record = model.save(tmp_path / "m.joblib")
    before = (path.read_bytes(), record.read_bytes())
    other = LearnedMap(model.models, {**model.meta, "note": "a newer model"})
    real = os.fsync
    calls = []

    def fsync(fd):
        calls.append(fd)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    with pytest.raises(OSError, match="No space left on device") as err:
        other.save(path)
    assert err.value.filename == str(record)
    assert (path.read_bytes(), record.read_bytes()) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.joblib", "m.json"]
    monkeypatch.setattr(os, "fsync", real)
    other.save(path)  # and a save that works replaces both
    assert LearnedMap.load(path).meta["note"] == "a newer model"


def test_a_map_predicted_in_row_chunks_is_the_single_call_s_to_the_bit(model, monkeypatch):
    from simlunar.features import learned as learned_mod

    img, _ = planted_pair(200)
    reg = model.model_for(DENSITY)
    x = image_features(img, pitch=pitch_of(DENSITY)).reshape(-1, len(FEATURE_NAMES))
    one = reg.predict(x)
    parts = []

    class Spy:  # records the chunks predicted
        def predict(self, part):
            parts.append(len(part))
            return reg.predict(part)

    monkeypatch.setattr(learned_mod, "PREDICT_CHUNK_ROWS", 1000)
    for cores in (1, 2, 3):
        parts.clear()
        y = learned_mod.predict_rows(Spy(), x, cores=cores)
        np.testing.assert_array_equal(y, one)
        # 12 288 rows: one chunk per core (each at least 1000 rows), all rows once
        assert len(parts) == cores and sum(parts) == len(x)
    # the map itself: chunked (small threshold) equals one call (large threshold)
    chunked = model.predict(img, density=DENSITY)
    monkeypatch.setattr(learned_mod, "PREDICT_CHUNK_ROWS", 10**9)
    np.testing.assert_array_equal(chunked, model.predict(img, density=DENSITY))
