"""Every file a unit reads is in its cache key by construction: an option that names a file is
declared as such (``option(..., file=...)``, ``Annotated[..., FileOption(...)]``), and the key
hashes every declared file found by walking the declarations. These tests walk every options
class and every config model, so a file option added without its marker, or one the walk does
not reach, fails here before a stale result is ever served."""

from __future__ import annotations

import dataclasses
import re
import types
import typing
from pathlib import Path

import pytest
from pydantic import BaseModel

from simlunar.config.derived import ComponentList
from simlunar.config.schema import ExperimentCfg
from simlunar.pipeline.inputs import (
    declared_files,
    input_files,
    input_hashes,
    model_files,
    model_inputs,
)
from simlunar.pipeline.runner import unit_key
from simlunar.pipeline.unit_models import model_class
from simlunar.registry import FileOption, Options, file_option, option_info


def _options_classes() -> list[type]:
    """Every options class of the library (imported with the config schema)."""
    import simlunar.features.learned
    import simlunar.reconstruction.learned  # noqa: F401

    out, todo = [], list(Options.__subclasses__())
    while todo:
        cls = todo.pop()
        if cls not in out:
            out.append(cls)
            todo.extend(cls.__subclasses__())
    return [c for c in out if dataclasses.is_dataclass(c)]


def _members(ann):
    """(annotation, metadata) pairs reachable through Annotated, unions, dicts and lists."""
    origin, args = typing.get_origin(ann), typing.get_args(ann)
    if origin is typing.Annotated:
        yield args[0], args[1:]
        yield from _members(args[0])
    elif origin in (typing.Union, types.UnionType, list, tuple, dict):
        for a in args:
            yield a, ()
            yield from _members(a)


def _models(root=ExperimentCfg) -> list[type[BaseModel]]:
    """Every pydantic model reachable from ``root``'s annotations."""
    seen, todo = [], [root]
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        seen.append(m)
        for info in m.model_fields.values():
            for a, _ in [(info.annotation, ()), *_members(info.annotation)]:
                if isinstance(a, type) and issubclass(a, BaseModel):
                    todo.append(a)
    return seen


def _samples(model, path: str, value: str) -> list[tuple[dict, str, FileOption]]:
    """Plain configs holding ``value`` at one declared file option each: (config, key path,
    marker), made from the declarations alone (what the key's walk must then find)."""
    out = []
    for name, info in model.model_fields.items():
        key = info.alias or name
        for plain, where, marker in _field_samples(info.annotation, info.metadata, value):
            out.append(({key: plain}, f"{path}{key}{where}", marker))
    return out


def _field_samples(ann, metadata, value):
    for m in metadata:
        if isinstance(m, FileOption):
            return [(value, "", m)]
        if isinstance(m, ComponentList):
            got = []
            for name, entry in m.registry.items():
                for fname, row in option_info(entry.options).items():
                    if file_option(row) is not None:
                        got.append(([{name: {fname: value}}], f".{name}.{fname}", file_option(row)))
            return got
    return _type_samples(ann, value)


def _type_samples(ann, value):
    origin, args = typing.get_origin(ann), typing.get_args(ann)
    if origin is typing.Annotated:
        return _field_samples(args[0], args[1:], value)
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        return [(plain, f".{where}", m) for plain, where, m in _samples(ann, "", value)]
    if origin in (typing.Union, types.UnionType):
        return [s for a in args for s in _type_samples(a, value)]
    if origin is dict and len(args) == 2:
        return [({"x": p}, f".x{w}", m) for p, w, m in _type_samples(args[1], value)]
    if origin in (list, tuple) and args:
        return [([p], f"[0]{w}", m) for p, w, m in _type_samples(args[0], value)]
    return []


def _declared_markers() -> list[tuple[str, FileOption]]:
    """(where, marker) of every file option declared in an options class or a config model."""
    out = []
    for cls in _options_classes():
        for f in dataclasses.fields(cls):
            if file_option(f) is not None:
                out.append((f"{cls.__name__}.{f.name}", file_option(f)))
    for m in _models():
        for name, info in m.model_fields.items():
            if file_option(info) is not None:
                out.append((f"{m.__name__}.{name}", file_option(info)))
    return out


def test_the_library_declares_its_file_options():
    # the file options that exist today: a removed marker (a file read but not hashed) fails
    where = {w for w, _ in _declared_markers()}
    assert {
        "LearnedMapOptions.model",
        "LearnedReconOptions.model",
        "TerrainCfg.file",
        "TerrainCfg.albedo_file",
        "TerrainCfg.preset",
    } <= where


def test_every_declared_file_option_is_reached_by_the_cache_key(tmp_path):
    """Each declared file option, set in a plain config built from the declarations, is in
    :func:`input_files`, and new bytes at the same path give another unit key."""
    f = tmp_path / "input.joblib"
    f.write_bytes(b"one")
    samples = [(c, w.lstrip("."), m) for c, w, m in _samples(ExperimentCfg, "", str(f))]
    reached = {id(m) for _, _, m in samples}
    for where, marker in _declared_markers():
        assert id(marker) in reached, f"{where}: a file option no config key path reaches"
    for config, where, marker in samples:
        if marker.kind == "preset":
            continue  # a name, not a path (its own test below)
        files = input_files(config)
        assert files.get(where) == f, f"{where} is not in the unit's input files"
        if marker.kind == "model":
            assert files[f"{where}.json"] == f.with_suffix(".json")
            f.with_suffix(".json").write_text("{}")
        before = unit_key(config, input_hashes(config))
        f.write_bytes(b"two")
        assert unit_key(config, input_hashes(config)) != before, where
        f.write_bytes(b"one")


def _looks_like_a_file(name: str, doc: str | None, ann) -> bool:
    text = f"{doc or ''}"
    return (
        name in ("file", "model", "path", "mask", "table")
        or name.endswith(("_file", "_path", "_mask_file", "_table_file"))
        or bool(re.search(r"\b(model|DEM|mask|table|grid) file\b|\.joblib|\.npy\b", text))
        or "Path" in str(ann)
    )


def test_an_option_that_names_a_file_is_declared_as_one():
    """A field whose name, doc or type says it names a file carries the file marker (else a
    file replaced at the same path would be served from the cache)."""
    bad = []
    for cls in _options_classes():
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            doc = f.metadata.get("doc")
            if doc is None or f.metadata.get("choices") is not None:
                continue  # set by the library, or a choice of names
            if _looks_like_a_file(f.name, doc, hints.get(f.name)) and file_option(f) is None:
                bad.append(f"{cls.__name__}.{f.name}")
    for m in _models():
        for name, info in m.model_fields.items():
            if name in ("name", "kind", "description") or "Literal" in str(info.annotation):
                continue
            if _looks_like_a_file(name, info.description, info.annotation) and (
                file_option(info) is None
            ):
                bad.append(f"{m.__name__}.{name}")
    # known non-files: option names that mean something else
    allowed = {"OrenNayarBSDF.model", "OrenNayarCfg.model"}
    assert sorted(set(bad) - allowed) == []


def test_every_model_format_has_its_loader():
    # a new trained-model option must name a format some container reads, or preflight
    # cannot check it before work
    for where, marker in _declared_markers():
        if marker.kind == "model":
            assert model_class(marker.format).FORMAT == marker.format, where
    with pytest.raises(TypeError, match="no model container"):
        model_class("simlunar-nothing/1")


def test_learned_map_keys_keep_their_names():
    # the key paths of caches made before the walk: a learned map's model and record
    study = {"strategy_options": {"l": {"strategy": "learned", "feature_opts": {"model": "m.joblib"}}}}  # fmt: skip
    assert model_files(study) == {
        "study.strategy_options.l.feature_opts.model": Path("m.joblib"),
        "study.strategy_options.l.feature_opts.model.json": Path("m.json"),
    }


def test_learned_reconstruction_model_is_an_input_under_its_label():
    study = {"reconstructions": ["linear", {"learned": {"model": "r.joblib"}},
                                 {"mine": {"reconstruction": "learned", "model": "q.joblib"}}]}  # fmt: skip
    assert model_files(study) == {
        "study.reconstructions.learned.model": Path("r.joblib"),
        "study.reconstructions.learned.model.json": Path("r.json"),
        "study.reconstructions.mine.model": Path("q.joblib"),
        "study.reconstructions.mine.model.json": Path("q.json"),
    }
    # a label with a dot (a path's separator) still names its own file
    dotted = {"reconstructions": [{"my.model": {"reconstruction": "learned", "model": "d.joblib"}}]}
    assert model_files(dotted)["study.reconstructions.my.model.model"] == Path("d.joblib")
    kinds = model_inputs({"study": study})
    assert {m.format for m in kinds.values()} == {"simlunar-learned-reconstruction/1"}


@pytest.mark.parametrize(
    "study",
    [
        {"reconstructions": "linear"},
        {"reconstructions": [{"learned": None}]},
        {"reconstructions": [{"nope": {"model": "x.joblib"}}]},
        {"reconstructions": [1, {"a": 1, "b": 2}]},
        {"strategy_options": ["l"]},
        {"strategy_options": {"l": {"feature_opts": "m.joblib"}}},
        {"reconstructions": [{"learned": {"model": 5}}]},
        {"strategy_options": {"l": {"feature_opts": {"model": ["a.joblib"]}}}},
    ],
)
def test_the_walk_survives_malformed_plain_configs(study):
    # the walk runs on plain dicts before the schema has spoken: it must not raise on them
    assert model_files(study) == {}


def test_declared_files_of_a_preset_config():
    assert declared_files({"terrain": {"preset": "aerial_1"}})["terrain.preset"].kind == "preset"
    assert input_files({"terrain": {"preset": "no_such_preset_xyz"}}) == {}


# --- a retrained learned-reconstruction model -------------------------------------------------
@pytest.fixture(scope="module")
def recon_models(tmp_path_factory) -> dict[str, Path]:
    """Two learned-reconstruction models of different bytes (trained on two seeds)."""
    import numpy as np
    from scipy import ndimage

    from simlunar.features.learned import LearnedOptions
    from simlunar.planner.learning import train_learned_reconstruction

    def pair(seed):
        r = np.random.default_rng(seed)
        d = ndimage.gaussian_filter(r.standard_normal((32, 40)), 1.5)
        z = ndimage.gaussian_filter(r.standard_normal((32, 40)), 8) * 20 + d / d.std()
        return np.clip(0.5 + 0.15 * d / d.std(), 0.01, None), z

    root = tmp_path_factory.mktemp("recon_models")
    out = {}
    for name, seed in (("a", 0), ("b", 7)):
        m = train_learned_reconstruction(
            [pair(seed + i) for i in range(2)],
            densities=(1 / 16,),
            options=LearnedOptions(layouts=1, pixels_per_example=400, max_iter=5),
            rng=seed,
        )
        out[name], _ = m.save(root / name / "r.joblib")
    assert out["a"].read_bytes() != out["b"].read_bytes()
    return out


def _install(src: Path, dst: Path) -> None:
    import shutil

    dst.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(src, dst)
    shutil.copyfile(src.with_suffix(".json"), dst.with_suffix(".json"))


def _recon_cfg(model: Path):
    from simlunar.config.loading import validate_data

    return validate_data(
        {"name": "retrain", "seed": 3,
         "terrain": {"preset": "aerial_1", "scale": 0.04},
         "render": {"spp": 1, "max_depth": 2},
         "study": {"strategies": ["random"], "densities": ["1/16"], "trials": 1,
                   "metrics": ["mse"], "score_region": "full"},
         "sweep": {"study.reconstructions": [["linear"],
                                             ["linear", {"learned": {"model": str(model)}}]]},
         "figures": {"enabled": False}}
    )  # fmt: skip


def test_a_retrained_reconstruction_model_changes_exactly_the_keys_of_its_units(
    recon_models, tmp_path
):
    from simlunar.pipeline.runner import expand

    model = tmp_path / "models" / "r.joblib"
    _install(recon_models["a"], model)
    a = [u.key for u in expand(_recon_cfg(model))]
    _install(recon_models["b"], model)  # retrained: same path, other bytes
    b = [u.key for u in expand(_recon_cfg(model))]
    assert a[0] == b[0]  # the unit without the model keeps its key
    assert a[1] != b[1]  # the unit that reads it does not


@pytest.mark.slow
def test_a_retrained_reconstruction_model_is_recomputed_not_served_stale(recon_models, tmp_path):
    from simlunar.pipeline.executors import LocalPoolExecutor
    from simlunar.pipeline.runner import run_experiment

    model = tmp_path / "models" / "r.joblib"
    _install(recon_models["a"], model)
    out = tmp_path / "out"
    s = run_experiment(_recon_cfg(model), out, executor=LocalPoolExecutor(1), progress=False)
    assert (s.units_computed, s.units_cached) == (2, 0)
    _install(recon_models["b"], model)
    s = run_experiment(_recon_cfg(model), out, executor=LocalPoolExecutor(1), progress=False)
    assert (s.units_computed, s.units_cached) == (1, 1)
    s = run_experiment(_recon_cfg(model), out, executor=LocalPoolExecutor(1), progress=False)
    assert (s.units_computed, s.units_cached) == (0, 2)
