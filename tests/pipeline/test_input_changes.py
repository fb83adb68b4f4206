"""A file a run's units read changes during the run: no unit is stored under a key that names
other content, the run stops in one line, and a rerun with the file restored gives the clean
run's results byte for byte."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from simlunar.config.loading import validate_data
from simlunar.errors import InputChangedError
from simlunar.pipeline.executors import LocalPoolExecutor
from simlunar.pipeline.inputs import input_hashes
from simlunar.pipeline.runner import expand, run_experiment
from simlunar.pipeline.unit import compute_unit
from simlunar.pipeline.unit_models import read_unit_models, verify_inputs


def _train(seed: int):
    from scipy import ndimage

    from simlunar.features.learned import LearnedOptions
    from simlunar.planner.learning import train_learned_map

    gen = np.random.default_rng(seed)
    pairs = []
    for _ in range(2):
        z = ndimage.gaussian_filter(gen.standard_normal((48, 64)), 3) * 5
        img = np.clip(0.5 + ndimage.gaussian_filter(gen.standard_normal((48, 64)), 1), 0.01, 1)
        pairs.append((img, z))
    opts = LearnedOptions(pixels_per_example=500, max_iter=5)
    return train_learned_map(pairs, densities=[1 / 16], options=opts, rng=seed)


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> dict[str, Path]:
    """Two different valid models (A, B), each a .joblib with its .json record."""
    root = tmp_path_factory.mktemp("models")
    out = {}
    for name, seed in (("a", 0), ("b", 5)):
        path, _ = _train(seed).save(root / name / "m.joblib")
        out[name] = path
    assert out["a"].read_bytes() != out["b"].read_bytes()
    return out


def _install(src: Path, dst: Path) -> None:
    dst.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(src, dst)
    shutil.copyfile(src.with_suffix(".json"), dst.with_suffix(".json"))


def _cfg(model: Path):
    return validate_data(
        {"name": "swap", "seed": 3,
         "terrain": {"preset": "aerial_1", "scale": 0.04},
         "render": {"spp": 1, "max_depth": 2},
         "study": {"strategies": ["random", "l"],
                   "strategy_options": {"l": {"strategy": "learned",
                                              "feature_opts": {"model": str(model)}}},
                   "densities": ["1/16"], "trials": 1, "metrics": ["mse"]},
         "sweep": {"render.light.elevation_deg": [30, 45, 60]},
         "figures": {"enabled": False}}
    )  # fmt: skip


def _folder(out: Path) -> dict:
    """Every file's bytes but the run's times (provenance, a unit record's timings)."""
    files = {}
    for p in sorted(out.rglob("*")):
        if not p.is_file() or p.name == "provenance.json" or p.name.endswith(".lock"):
            continue
        if p.parent.name == "units" and p.suffix == ".json":
            rec = json.loads(p.read_text())
            rec.pop("timings")
            files[str(p.relative_to(out))] = rec
        else:
            files[str(p.relative_to(out))] = p.read_bytes()
    return files


def test_unit_key_names_the_model_content(models, tmp_path):
    model = tmp_path / "models" / "m.joblib"
    _install(models["a"], model)
    keys_a = [u.key for u in expand(_cfg(model))]
    _install(models["b"], model)
    keys_b = [u.key for u in expand(_cfg(model))]
    assert len(set(keys_a)) == 3 and not set(keys_a) & set(keys_b)


@pytest.mark.slow
def test_model_swapped_between_units_stops_the_run_and_a_restored_rerun_is_clean(
    models, tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    model = Path("models") / "m.joblib"  # relative, as experiments name them
    _install(models["a"], model)
    clean = tmp_path / "clean"
    s = run_experiment(_cfg(model), clean, executor=LocalPoolExecutor(1), progress=False)
    assert s.units_computed == 3

    done = []

    def swap_after_first(payload, **kw):
        rec = compute_unit(payload, **kw)
        if not done:  # another valid model replaces the file between unit 1 and unit 2
            _install(models["b"], model)
        done.append(payload["config"]["render"]["light"]["elevation_deg"])
        return rec

    out = tmp_path / "swapped"
    with pytest.raises(InputChangedError) as err:
        run_experiment(
            _cfg(model), out, executor=LocalPoolExecutor(1), compute=swap_after_first,
            progress=False,
        )  # fmt: skip
    msg = str(err.value)
    assert "\n" not in msg
    assert msg.startswith("study.strategy_options.l.feature_opts.model: models/m.joblib changed")
    assert "1 of 3 units finished and kept" in msg
    assert done == [30]  # the second unit stopped before computing anything
    # the one unit stored is model A's, under model A's key
    stored = {p.name.split(".")[0] for p in (out / "units").iterdir()}
    _install(models["a"], model)
    a_keys = [u.key for u in expand(_cfg(model))]
    assert stored and stored <= {a_keys[0]}
    assert not (out / "results.csv").exists()

    # model A restored: the rerun reuses the first unit and computes the others with A
    s = run_experiment(_cfg(model), out, executor=LocalPoolExecutor(1), progress=False)
    assert (s.units_cached, s.units_computed) == (1, 2)
    assert _folder(out) == _folder(clean)
    assert (out / "results.csv").read_bytes() == (clean / "results.csv").read_bytes()


def test_unit_loads_the_model_from_the_bytes_it_hashed(models, tmp_path):
    model = tmp_path / "m.joblib"
    _install(models["a"], model)
    cfg = {"study": {"strategy_options": {"l": {"feature_opts": {"model": str(model)}}}}}
    inputs = input_hashes(cfg)
    got = read_unit_models(inputs, cfg)
    digest, learned_map = got[str(model)]
    assert digest == inputs["study.strategy_options.l.feature_opts.model"]["sha256"]
    assert learned_map.meta["model_sha256"] == digest
    verify_inputs(inputs)
    _install(models["b"], model)
    with pytest.raises(InputChangedError, match=r"feature_opts\.model: .*m\.joblib changed"):
        read_unit_models(inputs, cfg)
    with pytest.raises(InputChangedError, match="changed during the run"):
        verify_inputs(inputs)
    # a record replaced alone is caught too
    _install(models["a"], model)
    shutil.copyfile(models["b"].with_suffix(".json"), model.with_suffix(".json"))
    with pytest.raises(InputChangedError, match=r"model\.json: .*m\.json changed"):
        read_unit_models(inputs, cfg)


def test_a_pinned_model_is_used_even_after_its_file_is_replaced(models, tmp_path):
    from simlunar.features.learned import LearnedMap, learned, pinned_models

    model = tmp_path / "m.joblib"
    _install(models["a"], model)
    image = np.random.default_rng(0).uniform(0.1, 0.9, (40, 50))
    a = LearnedMap.load(models["a"])
    want_a = a.predict(image, density=1 / 16)
    want_b = LearnedMap.load(models["b"]).predict(image, density=1 / 16)
    assert not np.allclose(want_a, want_b)
    digest = json.loads(model.with_suffix(".json").read_text())["model_sha256"]
    with pinned_models({model: (digest, a)}):
        _install(models["b"], model)
        np.testing.assert_array_equal(learned(image, model=model, density=1 / 16), want_a)
        # a second holder with other content for the same path is refused
        with pytest.raises(ValueError, match="changed during the run"):
            with pinned_models({model: ("0" * 64, a)}):
                pass
    # unpinned: the file as it is now
    np.testing.assert_array_equal(learned(image, model=model, density=1 / 16), want_b)
