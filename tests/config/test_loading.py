"""The experiment schema: defaults, unit conversion, sweeps and one-line errors with key paths."""

from __future__ import annotations

import math
import re

import pytest
import yaml

from simlunar.config.docs import json_schema
from simlunar.config.loading import apply_sweep_value, load_experiment, validate_data
from simlunar.config.schema import ExperimentCfg
from simlunar.config.yamlio import parse_set
from simlunar.errors import ConfigError


def base(**over) -> dict:
    d = {
        "name": "t",
        "seed": 1,
        "terrain": {"preset": "aerial_1", "scale": 0.125},
        "study": {
            "strategies": ["random", "wavelet"],
            "densities": ["1/2", "1/8"],
            "trials": 2,
            "metrics": ["mse"],
        },
    }
    d.update(over)
    return d


def model(d: dict) -> ExperimentCfg:
    """Schema-level validation only (no registry look-ups)."""
    return ExperimentCfg.model_validate(d)


def test_defaults_and_units_are_converted_once():
    cfg = model(
        base(
            render={
                "light": {"elevation_deg": "0.5 rad", "azimuth_deg": 90},
                "bsdf": {"kind": "oren_nayar", "sigma_deg": 20},
            }
        )
    )
    assert cfg.render.light.kind == "sun"
    assert cfg.render.light.elevation_deg == pytest.approx(math.degrees(0.5))
    assert cfg.render.light.elevation == pytest.approx(0.5)
    assert cfg.render.light.azimuth == pytest.approx(math.pi / 2)
    assert cfg.render.bsdf.sigma == pytest.approx(math.radians(20))
    assert cfg.render.camera.kind == "orthographic_nadir"
    assert cfg.study.kind == "sampling"
    assert cfg.study.densities == [0.5, 0.125]


def test_density_range_form():
    cfg = model(base(study={"densities": {"from": "1/2", "to": "1/2048", "count": 11}}))
    assert cfg.study.densities == [2.0**-i for i in range(1, 12)]


def test_sweeping_a_kind_resets_its_section():
    d = base(render={"light": {"kind": "sun", "elevation_deg": 30}})
    out = apply_sweep_value(d, "render.light.kind", "camera")
    assert out["render"]["light"] == {"kind": "camera"}
    assert d["render"]["light"]["elevation_deg"] == 30  # the input is not modified
    assert model(out).render.light.kind == "camera"


def test_parse_set_reads_yaml_values():
    assert parse_set(
        ["render.spp=32", "study.strategies=[grid, random]", "render.bsdf.kind=lambert"]
    ) == {"render.spp": 32, "study.strategies": ["grid", "random"], "render.bsdf.kind": "lambert"}
    with pytest.raises(ConfigError, match=r"expected key\.path=value"):
        parse_set(["render.spp"])


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (
            lambda d: d["render"].update(light={"elevation_rad": 0.3}),
            "render.light.elevation_rad: unknown key (valid keys: kind, elevation_deg, azimuth_deg",
        ),
        (lambda d: d.update(colour="red"), "colour: unknown key"),
        (lambda d: d["render"].update(spp="many"), "render.spp: Input should be a valid integer"),
        (
            lambda d: d["render"].update(light={"elevation_deg": "30 furlong"}),
            "render.light.elevation_deg: bad unit 'furlong'",
        ),
        (
            lambda d: d["render"].update(light={"elevation_deg": 120}),
            "render.light.elevation_deg: Input should be less than or equal to 90",
        ),
        (
            lambda d: d["render"].update(light={"kind": "moon"}),
            "render.light: kind must be one of sun, camera",
        ),
        (
            lambda d: d["study"].update(densities=["1/2", "3/2"]),
            "study.densities[1]: a density must lie in (0, 1]",
        ),
        (
            lambda d: d["study"].update(densities={"from": "1/2", "to": "1/8"}),
            "study.densities.count: Field required",
        ),
        (
            lambda d: d.update(terrain={"preset": "aerial_1", "file": "x.npy"}),
            "terrain: give exactly one of preset or file",
        ),
        (
            lambda d: d.update(sweep={"render.light.elevation": [5, 10]}),
            "sweep.render.light.elevation: no such key in the experiment schema (valid keys under "
            "render.light: kind, elevation_deg",
        ),
        (
            lambda d: d.update(sweep={"render.lamp.elevation_deg": [5]}),
            "sweep.render.lamp.elevation_deg: no such key",
        ),
        (
            lambda d: d.update(sweep={"render.light.elevation_deg": [5, 95]}),
            "sweep.render.light.elevation_deg[1]: render.light.elevation_deg: Input should be less",
        ),
        (
            lambda d: d.update(terrain={"file": "nowhere.npy", "spacing_m": 0.2}),
            "terrain.file: file not found",
        ),
    ],
)
def test_errors_name_the_key_path(mutate, message, tmp_path):
    d = base(render={})
    mutate(d)
    with pytest.raises(ConfigError) as exc:
        validate_data(d, base_dir=tmp_path)
    text = str(exc.value)
    assert "\n" not in text
    assert text.startswith(message), text


def test_registry_names_are_checked():
    with pytest.raises(
        ConfigError, match=r"^terrain.preset: unknown terrain preset 'mars_1' \(valid: .*aerial_1"
    ):
        validate_data(base(terrain={"preset": "mars_1"}))
    with pytest.raises(
        ConfigError, match=r"^study.strategies\[1\]: unknown strategy 'wavlet' \(valid: .*wavelet"
    ):
        validate_data(base(study={"strategies": ["random", "wavlet"], "densities": [0.5]}))
    with pytest.raises(ConfigError, match=r"^study.metrics\[0\]: unknown metric 'psnr'"):
        validate_data(base(study={"metrics": ["psnr"], "densities": [0.5]}))


def test_labelled_strategy_variants_are_checked_by_their_base():
    opts = {"wavelet_bn": {"strategy": "wavelet", "blue_noise": True}}
    cfg = validate_data(
        base(
            study={
                "strategies": ["random", "wavelet_bn"],
                "densities": [0.5],
                "strategy_options": opts,
            }
        )
    )
    o = cfg.study.strategy_options["wavelet_bn"]
    assert (o.strategy, o.blue_noise, o.uniform_mix) == ("wavelet", True, 0.0)
    # a label without a base strategy is an unknown strategy; a bad base names the label
    with pytest.raises(ConfigError, match=r"^study.strategies\[1\]: unknown strategy 'wavelet_bn'"):
        validate_data(base(study={"strategies": ["random", "wavelet_bn"], "densities": [0.5]}))
    bad = {"wavelet_bn": {"strategy": "wavlet"}}
    with pytest.raises(
        ConfigError,
        match=r"^study.strategies\[1\] \(wavelet_bn\).strategy: unknown strategy 'wavlet'",
    ):
        validate_data(
            base(
                study={
                    "strategies": ["random", "wavelet_bn"],
                    "densities": [0.5],
                    "strategy_options": bad,
                }
            )
        )


def test_load_experiment_prefixes_the_file_and_applies_overrides(tmp_path):
    p = tmp_path / "e.yaml"
    p.write_text(yaml.safe_dump(base()))
    cfg = load_experiment(p, {"render.spp": 4, "render.light.kind": "camera"})
    assert cfg.render.spp == 4 and cfg.render.light.kind == "camera"
    with pytest.raises(ConfigError, match=r"^--set render.spq: no such key"):
        load_experiment(p, {"render.spq": 4})
    p.write_text("name: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML at line"):
        load_experiment(p)
    with pytest.raises(FileNotFoundError, match="experiment file not found"):
        load_experiment(tmp_path / "missing.yaml")


def test_set_adds_a_labelled_strategy_and_checks_the_keys_inside_it(tmp_path):
    # study.strategy_options is a mapping with free labels: --set of a new label used to be
    # refused as "no such key" with the option keys listed as if they were the labels
    p = tmp_path / "e.yaml"
    d = base()
    d["study"]["strategy_options"] = {
        "wavelet_lloyd": {"strategy": "wavelet", "placement": "lloyd"}
    }
    d["study"]["strategies"] = ["random", "wavelet_lloyd"]
    p.write_text(yaml.safe_dump(d))
    cfg = load_experiment(
        p,
        {
            "study.strategies": ["random", "wavelet_lloyd", "lloyd_half"],
            "study.strategy_options.lloyd_half": {"strategy": "wavelet", "placement": "lloyd"},
            "study.strategy_options.wavelet_lloyd.uniform_mix": 0.5,
        },
    )
    assert cfg.study.strategy_options["lloyd_half"].placement == "lloyd"
    assert cfg.study.strategy_options["wavelet_lloyd"].uniform_mix == 0.5
    with pytest.raises(
        ConfigError,
        match=r"--set study.strategy_options.wavelet_lloyd.placemnt: no such key in the "
        r"experiment schema \(valid keys under study.strategy_options.wavelet_lloyd: placement,",
    ):
        load_experiment(p, {"study.strategy_options.wavelet_lloyd.placemnt": "lloyd"})
    with pytest.raises(ConfigError, match=r"study.strategy_options.x.placemnt: unknown key"):
        load_experiment(p, {"study.strategy_options.x": {"placemnt": "lloyd"}})
    # a sweep over one option of one labelled strategy
    d["sweep"] = {"study.strategy_options.wavelet_lloyd.uniform_mix": [0.0, 0.5]}
    cfg = validate_data(d)
    assert cfg.sweep["study.strategy_options.wavelet_lloyd.uniform_mix"] == [0.0, 0.5]


def test_json_schema_forbids_unknown_keys():
    s = json_schema()
    assert s["title"] == "simlunar experiment"
    assert s["additionalProperties"] is False
    assert set(s["required"]) == {"name", "terrain", "study"}
    assert s["$defs"]["SunLightCfg"]["additionalProperties"] is False
    assert "elevation_deg" in s["$defs"]["SunLightCfg"]["properties"]


def test_fig4_roughness_options_defaults_units_and_errors():
    import math as m

    from simlunar.config.schema import FiguresCfg

    f = FiguresCfg()
    assert f.sparse_mesh_sigma_deg == (20.0, 45.0) and f.sparse_mesh_roughness_threshold == 0.8
    assert f.sparse_mesh_sigma == pytest.approx((m.radians(20.0), m.radians(45.0)))
    g = FiguresCfg(sparse_mesh_sigma_deg=["0.1 rad", 30], sparse_mesh_roughness_threshold=None)
    assert g.sparse_mesh_sigma == pytest.approx((0.1, m.radians(30.0)))
    assert FiguresCfg(sparse_mesh_sigma_deg=None).sparse_mesh_sigma is None
    for bad in ([50, 30], [10, 90], [-1, 10]):
        with pytest.raises(ValueError, match="sparse_mesh_sigma_deg"):
            FiguresCfg(sparse_mesh_sigma_deg=bad)
    with pytest.raises(ValueError, match="sparse_mesh_roughness_threshold"):
        FiguresCfg(sparse_mesh_roughness_threshold=1.5)


def test_misspellings_get_did_you_mean(tmp_path):
    d = base()
    d["study"]["metricz"] = ["mse"]
    with pytest.raises(ConfigError, match=r"study.metricz: unknown key \(valid keys: .*\) "
                       r"\(did you mean 'metrics'\?\)$"):  # fmt: skip
        validate_data(d)
    d = base()
    d["study"]["strategies"] = ["random", "wavlet"]
    with pytest.raises(ConfigError, match=r"study.strategies\[1\]: unknown strategy 'wavlet' "
                       r"\(valid: .*\) \(did you mean 'wavelet'\?\)$"):  # fmt: skip
        validate_data(d)
    d = base()
    d["terrain"]["preset"] = "moonyrd"
    with pytest.raises(ConfigError, match=r"\(did you mean 'moonyard'\?\)$"):
        validate_data(d)
    (tmp_path / "my_experiment.yaml").write_text(yaml.safe_dump(base()))
    with pytest.raises(FileNotFoundError, match=r"did you mean .*my_experiment\.yaml'\?\)$"):
        load_experiment(tmp_path / "my_experimnt.yaml")
    d = base()
    d["terrain"] = {"file": "dem_01.npy", "spacing_m": 0.2}
    (tmp_path / "dem_10.npy").write_bytes(b"")
    with pytest.raises(ConfigError, match=r"file not found: .*dem_01\.npy \(did you mean "):
        validate_data(d, base_dir=tmp_path)


def test_set_errors_name_the_set_not_the_file(tmp_path):
    p = tmp_path / "e.yaml"
    p.write_text(yaml.safe_dump(base()))
    with pytest.raises(ConfigError, match=r"^--set render.spp: Input should be greater"):
        load_experiment(p, {"render.spp": -1})
    with pytest.raises(ConfigError, match=r"^--set study.strategies: study.strategies\[0\]: "
                       r"unknown strategy 'wavlet'"):  # fmt: skip
        load_experiment(p, {"study.strategies": ["wavlet"]})
    with pytest.raises(ConfigError, match=r"^--set rendr.spp: no such key .* \(did you mean "
                       r"'render'\?\)$"):  # fmt: skip
        load_experiment(p, {"rendr.spp": 3})
    # a problem in the file itself still names the file, even with an unrelated --set
    d = base(render={"spp": 0})
    p.write_text(yaml.safe_dump(d))
    with pytest.raises(ConfigError, match=rf"^{re.escape(str(p))}: render.spp: "):
        load_experiment(p, {"study.trials": 2})


def test_set_changes_one_key_of_a_mapping(tmp_path):
    # study.densities written as {from, to, count}: --set of one of them keeps the others
    d = base()
    d["study"]["densities"] = {"from": "1/2", "to": "1/8", "count": 3}
    p = tmp_path / "e.yaml"
    p.write_text(yaml.safe_dump(d))
    assert load_experiment(p).study.densities == pytest.approx([0.5, 0.25, 0.125])
    cfg = load_experiment(p, {"study.densities.from": "1/32", "study.densities.to": "1/2"})
    assert cfg.study.densities == pytest.approx([1 / 32, 1 / 8, 1 / 2])
    with pytest.raises(ConfigError, match=r"^--set study.densities.form: no such key .*"
                       r"\(valid keys under study.densities: from, to, count\) "
                       r"\(did you mean 'from'\?\)$"):  # fmt: skip
        load_experiment(p, {"study.densities.form": "1/4"})
    with pytest.raises(ConfigError, match=r"^--set study.densities.from: a density must lie"):
        load_experiment(p, {"study.densities.from": 2})


def test_set_of_a_key_inside_a_value_that_is_no_mapping(tmp_path):
    p = tmp_path / "e.yaml"
    p.write_text(yaml.safe_dump(base()))  # densities: a list
    with pytest.raises(ConfigError, match=r"^--set study.densities.from: study.densities is a "
                       r"list in this file, not a mapping of keys; set it whole"):  # fmt: skip
        load_experiment(p, {"study.densities.from": "1/4"})
