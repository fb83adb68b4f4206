"""One typed configuration: editor schema, no free-form dicts, option models, value checks,
sweep normalisation, the translation module and the documented YAML reference."""

from __future__ import annotations

import csv
import dataclasses
import functools
import inspect
import math
import typing
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import yaml
from pydantic import BaseModel

from simlunar.config import render, scanner_translate, schema, studies, terrain, translate
from simlunar.config import scanner as scanner_cfg
from simlunar.config.docs import json_schema, schema_model
from simlunar.config.loading import validate_data
from simlunar.config.scene import SceneCfg
from simlunar.errors import ConfigError
from simlunar.planner import RandomDrawOptions

ROOT = Path(__file__).resolve().parents[2]


def base(**over) -> dict:
    d = {
        "name": "t",
        "seed": 1,
        "terrain": {"preset": "aerial_1", "scale": 0.125},
        "study": {"strategies": ["random", "wavelet"], "densities": [0.5], "trials": 1},
    }
    d.update(over)
    return d


def scanner(**study) -> dict:
    return base(study={"kind": "scanner", **study})


def error_of(data) -> str:
    with pytest.raises(ConfigError) as info:
        validate_data(data)
    return str(info.value)


# --------------------------------------------------------------------------- editor schema
def _kind_of(path: Path) -> str:
    if path.parent.name == "experiments":
        return "experiment"
    return "preset" if "grid" in yaml.safe_load(path.read_text()) else "scene"


@functools.cache
def _validator(kind: str):
    """The editor schema of ``kind`` checked against its meta-schema once (``jsonschema.validate``
    re-checks the whole schema on every call: 3 s each) and its validator, shared by the tests."""
    s = json_schema(kind)
    cls = jsonschema.validators.validator_for(s)
    cls.check_schema(s)
    return cls(s)


SHIPPED = sorted((ROOT / "experiments").glob("*.yaml")) + sorted((ROOT / "scenes").glob("*.yaml"))


@pytest.mark.parametrize("path", SHIPPED, ids=[f"{p.parent.name}/{p.name}" for p in SHIPPED])
def test_every_shipped_yaml_validates_against_the_editor_schema(path):
    kind = _kind_of(path)
    _validator(kind).validate(yaml.safe_load(path.read_text()))
    # and the models accept it too (the schema describes what they take)
    schema_model(kind).model_validate(yaml.safe_load(path.read_text()))


def test_editor_schema_accepts_the_input_forms_and_rejects_typos():
    s = _validator("experiment")
    ok = base(
        study={"densities": {"from": "1/2", "to": "1/8", "count": 3}, "trials": 1},
        render={"light": {"elevation_deg": "0.5 rad"}},
        figures={"panel_density": "1/32"},
    )
    s.validate(ok)
    # the co-located frame's two spellings, as the loader takes them
    for frame in ("camera", "ideal"):
        s.validate(base(render={"guide_frames": [frame]}))
    for bad in (
        base(render={"light": {"elevation_rad": 0.5}}),
        base(render={"guide_frames": ["idael"]}),
        scanner(options={"gray_opts": {"subpixle": True}}),
        base(study={"densities": [0.5], "strategy_options": {"x": {"blue_nois": True}}}),
        base(terrain={"preset": "aerial_1", "overrides": {"fractal": {"rms_mm": 1}}}),
        base(figures={"panel_density": "one half"}),
    ):
        with pytest.raises(jsonschema.ValidationError):
            s.validate(bad)


# --------------------------------------------------------------------------- no free dicts
def _models_from(model: type[BaseModel], seen: set) -> None:
    if model in seen:
        return
    seen.add(model)
    for f in model.model_fields.values():
        for m in _inner_models(f.annotation):
            _models_from(m, seen)


def _inner_models(ann) -> list:
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        return [ann]
    return [m for a in typing.get_args(ann) for m in _inner_models(a)]


def _free_form(ann) -> bool:
    """Any, bare dict / Mapping, or a dict whose values are not typed models."""
    if ann is typing.Any or ann in (dict, typing.Dict, typing.Mapping):  # noqa: UP006
        return True
    origin = typing.get_origin(ann)
    args = typing.get_args(ann)
    if origin is dict:
        value = args[1] if len(args) == 2 else typing.Any
        if not (isinstance(value, type) and issubclass(value, BaseModel)):
            return True
    return any(_free_form(a) for a in args if not isinstance(a, (str, int, float)))


def test_no_free_form_dict_field_in_the_config_models():
    models: set = set()
    for root in (schema.ExperimentCfg, SceneCfg, terrain.TerrainPresetCfg):
        _models_from(root, models)
    assert len(models) > 25  # the walk reaches the option models
    offenders = [
        f"{m.__name__}.{name}: {f.annotation}"
        for m in models
        for name, f in m.model_fields.items()
        # the sweep holds any YAML value per key path; each point is validated by the models
        if not (m is schema.ExperimentCfg and name == "sweep") and _free_form(f.annotation)
    ]
    assert offenders == []
    # the text of the model modules too (a field hidden from the walk still fails here)
    for mod in ("fields.py", "terrain.py", "render.py", "studies.py", "schema.py", "scene.py"):
        text = (ROOT / "simlunar" / "config" / mod).read_text()
        for pattern in ("dict[str, Any]", ": dict =", ": dict\n", "Dict[", "Mapping["):
            assert pattern not in text, f"{mod}: {pattern!r}"


def test_the_free_form_check_can_fail():
    assert _free_form(dict[str, typing.Any]) and _free_form(dict) and _free_form(typing.Any)
    assert _free_form(dict[str, dict[str, typing.Any]]) and _free_form(dict[str, float] | None)
    assert not _free_form(dict[str, studies.PlannerOptsCfg]) and not _free_form(float | None)


# --------------------------------------------------------------------------- option models
def _defaults(fn) -> dict:
    return {
        k: p.default
        for k, p in inspect.signature(fn).parameters.items()
        if p.default is not inspect.Parameter.empty
    }


def test_option_defaults_are_the_library_defaults():
    from simlunar.features import maps
    from simlunar.imaging.sensor import SensorModel
    from simlunar.render.capture import CaptureOptions
    from simlunar.scanner import rigs
    from simlunar.scanner.dot_scan import DotOptions
    from simlunar.scanner.gray_code import GrayCodeOptions
    from simlunar.study.scanner import aim_rig_at_terrain

    # the config's defaults are the library's options dataclasses' defaults
    # every coding's options block (derived from its registered options class)
    codings = scanner_translate.coding_options(scanner_cfg.ScannerOptionsCfg())
    assert codings["gray_code"] == GrayCodeOptions()
    from simlunar.scanner.codings import CODINGS

    assert codings == {n: e.options() for n, e in CODINGS.items()}
    assert scanner_translate.dot_options(scanner_cfg.DotOptsCfg()) == DotOptions()
    sparse = {k: v for k, v in vars(CaptureOptions()).items() if k.startswith("sparse_")}
    assert scanner_cfg.CaptureOptsCfg().model_dump() == sparse
    weighted = dataclasses.asdict(RandomDrawOptions())
    kw = translate.planner_kwargs("wavelet", studies.PlannerOptsCfg())
    assert {k: kw[k] for k in weighted} == weighted
    assert kw["feature_opts"] == _defaults(maps.wavelet)
    assert translate.planner_kwargs("entropy", studies.PlannerOptsCfg())["feature_opts"] == (
        _defaults(maps.entropy)
    )
    assert scanner_cfg.RigCfg().fill == _defaults(aim_rig_at_terrain)["fill"]
    make_rig = _defaults(rigs.RigCamera)  # the camera options of make_rig
    assert scanner_cfg.RigCfg().verge == make_rig["verge"]
    assert scanner_cfg.RigCfg().aperture_radius_m == make_rig["aperture_radius"]
    s, m = render.SensorCfg(), SensorModel()
    assert (s.full_well_e, s.read_noise_e, s.bits, s.response, s.gamma) == (
        m.full_well_e,
        m.read_noise_e,
        m.bits,
        m.response,
        m.gamma,
    )


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (
            scanner(options={"gray_opts": {"subpixle": True}}),
            "study.options.gray_opts.subpixle: unknown key (valid keys: black_threshold, "
            "white_threshold, inverses, method, require_reliable, subpixel)",
        ),
        (
            scanner(options={"dot_opts": {"radius": 1}}),
            "study.options.dot_opts.radius: unknown key",
        ),
        (scanner(options={"rig": {"cam_fov_x": 1.0}}), "study.options.rig.cam_fov_x: unknown key"),
        (scanner(options={"extra": 1}), "study.options.extra: unknown key"),
        (
            scanner(options={"planner_opts": {"grid": {}}}),
            "study.options.planner_opts.grid: not in study.planners (wavelet, random)",
        ),
        (
            scanner(options={"planner_opts": {"wavelet": {"feature_opts": {"levls": 1}}}}),
            "study.options.planner_opts.wavelet.feature_opts.levls: unknown key",
        ),
        (
            scanner(options={"planner_opts": {"wavelet": {"feature_opts": {"size": 5}}}}),
            "study.options.planner_opts.wavelet.feature_opts.size: not an option of the "
            "wavelet map (valid: boundary, levels, wavelet)",
        ),
        (
            scanner(rig="aerial", options={"rig": {"elevation_deg": 60}}),
            "study.options.rig.elevation_deg: not an option of the aerial rig",
        ),
        (
            base(study={"densities": [0.5], "strategy_options": {"w": {"blue_nois": True}}}),
            "study.strategy_options.w.blue_nois: unknown key",
        ),
        (
            base(
                study={
                    "strategies": ["random", "grid"],
                    "densities": [0.5],
                    "strategy_options": {"grid": {"uniform_mix": 0.5}},
                }
            ),
            "study.strategy_options.grid.uniform_mix: strategy 'grid' takes no options",
        ),
        (
            base(
                study={
                    "strategies": ["combination"],
                    "densities": [0.5],
                    "strategy_options": {"combination": {}},
                }
            ),
            "study.strategy_options.combination.coefficients: strategy 'combination' needs",
        ),
        (
            base(
                study={
                    "strategies": ["w"],
                    "densities": [0.5],
                    "strategy_options": {
                        "w": {"strategy": "wavelet", "feature_opts": {"wavelet": "db99"}}
                    },
                }
            ),
            "study.strategy_options.w.feature_opts.wavelet: unknown discrete wavelet 'db99'",
        ),
    ],
)
def test_option_typos_and_misfits_are_one_line_with_the_key_path(data, message):
    assert error_of(data).startswith(message)


def test_translation_converts_units_and_routes_feature_options():
    cfg = validate_data(
        scanner(
            options={
                "rig": {"cam_fov_x_deg": 60, "elevation_deg": "1 rad", "baseline_m": "30 cm"},
                "dot_opts": {"radius_px": 1.5},
                "planner_opts": {"wavelet": {"feature_opts": {"levels": 1}}},
            }
        )
    )
    rig = scanner_translate.rig_kwargs(cfg.study)
    assert rig["cam_fov_x"] == pytest.approx(math.pi / 3)
    assert rig["elevation"] == pytest.approx(1.0)
    assert rig["baseline"] == pytest.approx(0.3)
    assert "distance" not in rig and "fov_x" not in rig  # unset: the preset / fit decides
    opts = scanner_translate.scanner_options(cfg.study, cfg.render)
    assert opts.dots.radius == 1.5
    assert opts.planner_opts == {
        "wavelet": translate.planner_kwargs("wavelet", cfg.study.options.planner_opts["wavelet"])
    }
    assert opts.planner_opts["wavelet"]["feature_opts"]["levels"] == 1
    combo = studies.PlannerOptsCfg(
        coefficients={"wavelet": 1.0, "entropy": 0.5}, feature_opts={"levels": 2, "size": 5}
    )
    kw = translate.planner_kwargs("combination", combo)
    assert kw["coefficients"] == {"wavelet": 1.0, "entropy": 0.5}
    assert kw["feature_opts"]["wavelet"]["levels"] == 2
    assert kw["feature_opts"]["entropy"]["size"] == 5
    assert "size" not in kw["feature_opts"]["wavelet"]


def test_translated_options_run_through_the_planner():
    """The translated kwargs are accepted by the library (no TypeError at run time)."""
    from simlunar.planner import plan

    rng = np.random.default_rng(0)
    image = rng.random((32, 32))
    for base_name, opts in (
        ("wavelet", studies.PlannerOptsCfg(blue_noise=True, feature_opts={"levels": 1})),
        ("entropy", studies.PlannerOptsCfg(uniform_mix=0.3, feature_opts={"size": 5})),
        ("combination", studies.PlannerOptsCfg(coefficients={"gradient": 1, "wavelet": 2})),
        ("combination", studies.PlannerOptsCfg(coefficients={"uniform": 1, "entropy": 0.5})),
        ("random", studies.PlannerOptsCfg()),
    ):
        p = plan(base_name, 20, image=image, rng=1, **translate.planner_kwargs(base_name, opts))
        assert len(p.rows) == 20


# --------------------------------------------------------------------------- value checks
@pytest.mark.parametrize(
    ("data", "message"),
    [
        (
            base(render={"light": {"elevation_deg": 0}}),
            "render.light.elevation_deg: Input should be greater than 0",
        ),
        (
            base(render={"bsdf": {"kind": "oren_nayar", "sigma_deg": 90}}),
            "render.bsdf.sigma_deg: Input should be less than 90",
        ),
        (
            base(render={"light": {"irradiance": math.inf}}),
            "render.light.irradiance: Input should be a finite number",
        ),
        (
            base(render={"sensor": {"full_well_e": math.inf}}),
            "render.sensor.full_well_e: Input should be a finite number",
        ),
        (
            base(render={"sensor": {"gamma": math.nan}}),
            "render.sensor.gamma: Input should be a finite number",
        ),
        (
            base(
                render={
                    "camera": {
                        "kind": "perspective",
                        "width": 8,
                        "height": 8,
                        "fov_deg": 40,
                        "position_m": [1, 2, 3],
                        "look_at_m": [1, 2, 3],
                    }
                }
            ),
            "render.camera.look_at_m: equals position_m (the camera looks at its own position)",
        ),
        (scanner(projector_px=[0, 0]), "study.projector_px[0]: Input should be greater than 0"),
        (
            scanner(),
            None,  # replaced below: a fixed exposure in a scanner study
        ),
    ],
)
def test_values_that_failed_late_are_schema_errors(data, message):
    if message is None:
        data["render"] = {"sensor": {"exposure_e": 1000}}
        message = "render.sensor.exposure_e: a scanner study sets the exposure from its white"
    assert error_of(data).startswith(message)


# --------------------------------------------------------------------------- sweeps
def test_sweep_unit_strings_become_numbers_in_config_and_results(tmp_path):
    from fake_unit import fake_unit

    from simlunar.pipeline.runner import run_experiment

    data = base(
        study={"strategies": ["random", "grid"], "densities": ["1/2"], "trials": 1},
        sweep={
            "render.light.elevation_deg": [10, "0.5 rad", 60],
            "figures.panel_density": ["1/32"],
        },
    )
    cfg = validate_data(data)
    assert cfg.sweep["render.light.elevation_deg"] == [10, pytest.approx(math.degrees(0.5)), 60]
    run_experiment(cfg, tmp_path / "r", compute=fake_unit, progress=False, figures=False)
    with (tmp_path / "r" / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    column = sorted({r["render.light.elevation_deg"] for r in rows}, key=float)
    assert column == ["10", repr(math.degrees(0.5)), "60"]  # numbers, in degrees
    assert {r["figures.panel_density"] for r in rows} == {"0.03125"}
    resolved = yaml.safe_load((tmp_path / "r" / "config.yaml").read_text())
    assert resolved["sweep"]["render.light.elevation_deg"][1] == pytest.approx(28.6478897565)
    assert not any(isinstance(v, str) for v in resolved["sweep"]["render.light.elevation_deg"])
    assert all(isinstance(float(r["render.light.elevation_deg"]), float) for r in rows)


def test_sweep_keeps_plain_values_as_written():
    cfg = validate_data(base(sweep={"seed": [1, 2], "terrain.preset": ["aerial_1", "aerial_2"]}))
    assert cfg.sweep == {"seed": [1, 2], "terrain.preset": ["aerial_1", "aerial_2"]}


# --------------------------------------------------------------------------- presets
def test_a_bad_preset_file_is_one_line_naming_file_and_key(tmp_path):
    p = tmp_path / "mine.yaml"
    p.write_text(yaml.safe_dump({"grid": {"rows": 32, "cols": 32}, "fractal": {"hurst": 1.5}}))
    msg = error_of(base(terrain={"preset": str(p), "overrides": {"bed": {"amplitude_m": 0.1}}}))
    assert f"{p}: fractal.hurst: Input should be less than 1" in msg


# --------------------------------------------------------------------------- docs
def test_the_yaml_reference_in_the_docs_is_the_generated_one():
    from simlunar.config.docs import docs_block, reference_markdown

    text = (ROOT / "docs" / "experiments.md").read_text()
    block = docs_block(text)
    assert block is not None, "docs/experiments.md lost its schema-reference markers"
    assert block == reference_markdown(), "run: simlunar schema --markdown (update_docs)"
    for key in ("`subpixel`", "`cam_fov_x_deg`", "`blue_noise`", "`albedo_file`", "`rms_m`"):
        assert key in block


# --------------------------------------------------------------------------- albedo_file
def _dem_files(folder: Path, albedo_shape=(32, 48)):
    rng = np.random.default_rng(4)
    yy, xx = np.mgrid[0:32, 0:48]
    heights = 0.3 * np.sin(xx / 5.0) + 0.2 * np.cos(yy / 4.0) + 0.02 * rng.normal(size=(32, 48))
    albedo = np.where((xx // 8 + yy // 8) % 2 == 0, 0.08, 0.3)[: albedo_shape[0], : albedo_shape[1]]
    np.save(folder / "dem.npy", heights)
    np.save(folder / "alb.npy", albedo.astype(np.float32))
    return heights, albedo


@pytest.mark.render
def test_the_documented_albedo_file_example_runs_end_to_end(tmp_path):
    """docs/experiments.md: ``terrain: {file: dem.npy, albedo_file: alb.npy, spacing_m: 0.2}``
    (it crashed with load_dem() got an unexpected keyword argument 'albedo_file')."""
    from typer.testing import CliRunner

    from simlunar.cli import app
    from simlunar.results.store import UnitCache

    docs = (ROOT / "docs" / "experiments.md").read_text()
    example = "{file: dem.npy, albedo_file: alb.npy, spacing_m: 0.2}"
    assert example in docs
    _, albedo = _dem_files(tmp_path)
    text = f"""name: albedo_file
seed: 2
terrain: {example}
render: {{spp: 2, sensor: {{full_well_e: 20000, read_noise_e: 5, bits: 12}}}}
study: {{strategies: [random, wavelet], densities: [1/4, 1/16], trials: 1, metrics: [mse]}}
figures: {{enabled: false}}
"""
    (tmp_path / "exp.yaml").write_text(text)
    out = tmp_path / "res"
    r = CliRunner().invoke(
        app, ["run", str(tmp_path / "exp.yaml"), "--out", str(out), "--no-progress"]
    )
    assert r.exit_code == 0, r.output
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 * 2 and all(float(x["value"]) >= 0 for x in rows)
    key = next(p.stem for p in (out / "units").glob("*.json"))
    arrays = UnitCache(out).load_arrays(key)
    np.testing.assert_array_equal(arrays["albedo"], albedo.astype(np.float32))
    # the checkerboard albedo shows in the guide image: bright squares are brighter
    img = arrays["radiance"]
    assert img[albedo > 0.2].mean() > 2 * img[albedo < 0.2].mean()


def test_albedo_file_of_another_shape_is_one_line(tmp_path):
    from simlunar.config.translate import build_terrain

    _dem_files(tmp_path, albedo_shape=(32, 40))
    cfg = validate_data(
        base(terrain={"file": "dem.npy", "albedo_file": "alb.npy", "spacing_m": 0.2}),
        base_dir=tmp_path,
    )
    with pytest.raises(
        ValueError, match=r"^terrain.albedo_file: .*alb.npy: albedo shape 32 x 40 differs"
    ):
        build_terrain(cfg.terrain, rng=np.random.default_rng(0))
    msg = error_of(base(terrain={"preset": "aerial_1", "albedo_file": "alb.npy"}))
    assert msg == "terrain: albedo_file goes with a DEM file (give terrain.file)"


@pytest.mark.parametrize(
    "albedo",
    [
        np.full((2, 32, 48), 0.2),  # a [heights, albedo] stack: a DEM, not an albedo grid
        np.full((32, 48), 1.5),  # outside [0, 1]
        np.full((48, 32), 0.2),  # transposed
    ],
    ids=["stack", "range", "shape"],
)
def test_the_preflight_rejects_what_the_unit_would_reject(tmp_path, albedo):
    """One albedo reader: a file the unit refuses is refused before anything is written."""
    from simlunar.config.translate import build_terrain
    from simlunar.errors import ConfigError
    from simlunar.pipeline.inputs import terrain_facts

    _dem_files(tmp_path)
    np.save(tmp_path / "alb.npy", albedo)
    cfg = validate_data(
        base(terrain={"file": "dem.npy", "albedo_file": "alb.npy", "spacing_m": 0.2}),
        base_dir=tmp_path,
    )
    with pytest.raises(ValueError, match=r"^terrain.albedo_file: ") as unit_err:
        build_terrain(cfg.terrain, rng=np.random.default_rng(0))
    with pytest.raises(ConfigError, match=r"^terrain.albedo_file: ") as pre_err:
        terrain_facts(cfg.terrain)
    assert str(pre_err.value) == str(unit_err.value)


def test_the_schema_command_prints_what_the_test_validates_against(tmp_path):
    import json

    from typer.testing import CliRunner

    from simlunar.cli import app

    for kind in ("experiment", "scene", "preset"):
        r = CliRunner().invoke(app, ["schema", "--kind", kind])
        assert r.exit_code == 0, r.output
        assert json.loads(r.output) == json_schema(kind)
    r = CliRunner().invoke(app, ["schema", "--kind", "recipe"])
    assert r.exit_code == 2 and "--kind recipe: unknown document kind" in r.output
    r = CliRunner().invoke(app, ["schema", "--markdown"])
    assert r.exit_code == 0 and "#### `study.options.gray_opts`" in r.output


# --------------------------------------------------------------------------- keys with no effect
_PERSPECTIVE = {
    "kind": "perspective",
    "width": 32,
    "height": 24,
    "fov_deg": 30,
    "position_m": [0, 0, 60],
    "look_at_m": [0, 0, 0],
}


@pytest.mark.parametrize(
    "data, message",
    [
        (
            base(terrain={"preset": "aerial_1", "spacing_m": 200}),
            "terrain.spacing_m: the cell size of a DEM file (terrain.file) has no effect on a "
            "preset",
        ),
        (
            base(terrain={"file": "dem.npy", "spacing_m": 0.2, "scale": 0.5}),
            "terrain.scale: shrinks a preset's grid and has no effect on a DEM file",
        ),
        (
            base(render={"sensor": {"gamma": 1.8}}),
            "render.sensor.gamma: has no effect with response linear",
        ),
        (
            base(render={"camera": {**_PERSPECTIVE, "focus_distance_m": 60}}),
            "render.camera.focus_distance_m: has no effect on a pinhole camera",
        ),
        (
            scanner(options={"rig": {"focus_distance_m": 2.0}}),
            "study.options.rig.focus_distance_m: has no effect on a pinhole camera",
        ),
    ],
)
def test_a_key_without_effect_is_refused_in_one_line(data, message):
    # the silent trap these close: spacing_m: 200 on a preset was recorded in config.yaml and
    # ignored (results byte-identical to the 0.2 m run)
    assert error_of(data).startswith(message)


def test_the_keys_that_do_act_still_validate():
    validate_data(base(render={"sensor": {"response": "gamma", "gamma": 1.8}}))
    validate_data(
        base(render={"camera": {**_PERSPECTIVE, "aperture_radius_m": 0.01, "focus_distance_m": 60}})
    )
    validate_data(base(terrain={"preset": "aerial_1", "overrides": {"grid": {"spacing_m": 0.4}}}))


def test_a_misspelt_top_level_key_is_named_not_only_the_missing_one():
    data = base()
    data["studdy"] = data.pop("study")
    assert error_of(data).startswith("studdy: unknown key (valid keys: name, description")


def test_a_flash_frame_is_refused_in_a_scanner_study():
    # the scanner's co-located frame is its projector's flood frame (camera); a flash on the
    # rig is simulated for the sampling and LIDAR studies only
    data = scanner(guide_light="sun")
    data["render"] = {"guide_frames": [{"flash": {"baseline_m": 1, "sun_ratio": 1.0}}]}
    assert "a flash frame is not simulated in a scanner study" in error_of(data)
