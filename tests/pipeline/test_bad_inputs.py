"""`simlunar run` on bad input: every case exits 2 with one line on stderr and writes nothing.

Each case is run in-process through the Typer CLI. The check is strict: exit code 2, stdout
empty, exactly one stderr line starting ``error: `` and containing the expected words, no
traceback, and the SHA-256 of the whole test folder (the YAML, the input files, the output
folder when it exists beforehand) unchanged, so nothing was written anywhere. Almost every
case must fail in validation or in the preflight checks, before any render: the test module
runs in seconds.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.config.loading import set_path
from simlunar.pipeline.preflight import MAX_NAN_FRACTION

GOOD = {
    "name": "bad_input_test",
    "seed": 1,
    "terrain": {"preset": "aerial_1", "scale": 0.125},
    "study": {
        "strategies": ["random", "wavelet"],
        "densities": ["1/2", "1/8"],
        "trials": 2,
        "metrics": ["mse"],
    },
    "figures": {"enabled": False},
}
DEM = {"file": "dem.npy", "spacing_m": 0.2}
PERSPECTIVE = {
    "kind": "perspective",
    "width": 64,
    "height": 48,
    "fov_deg": 40,
    "position_m": [20.0, -12.0, 30.0],
    "look_at_m": [20.0, -12.5, 0.0],
}
SCANNER = {"kind": "scanner", "modes": ["gray_code"], "planners": ["random"], "budget": 0.1}


def with_(path: str, value, base: dict | None = None) -> dict:
    return set_path(base or GOOD, path, value)


def dem_cfg(**terrain) -> dict:
    return {**GOOD, "terrain": {**DEM, **terrain}}


# --------------------------------------------------------------------------- input files
def _heights(shape=(24, 32)) -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.normal(0.0, 0.3, shape)


def _npy(path: Path, arr) -> None:
    np.save(path, np.asarray(arr))


def files(**spec: Callable[[Path], None]):
    """A setup that writes files into the case folder: name -> writer(path)."""

    def setup(d: Path) -> None:
        for name, write in spec.items():
            write(d / name.replace("__", "."))

    return setup


def good_dem(p: Path) -> None:
    _npy(p, _heights())


def nan_dem(share: float):
    def write(p: Path) -> None:
        h = _heights()
        flat = h.ravel()
        flat[: int(np.ceil(share * flat.size))] = np.nan
        _npy(p, flat.reshape(h.shape))

    return write


def raw(data: bytes):
    return lambda p: p.write_bytes(data)


def npz(**arrays):
    return lambda p: np.savez(p, **arrays)


def a_file(p: Path) -> None:
    p.write_text("not a folder\n")


def read_only(p: Path) -> None:
    p.mkdir()


# --------------------------------------------------------------------------- cases
@dataclass
class Case:
    name: str
    data: dict | str
    expect: str
    args: tuple[str, ...] = ()
    setup: Callable[[Path], None] | None = None
    out: str = "results"
    marks: list = field(default_factory=list)


CASES = [
    # YAML itself
    Case("yaml syntax", "name: x\nterrain: {preset: aerial_1\n", "not valid YAML at line"),
    Case("yaml not a mapping", "- a\n- b\n", "<root>: expected a mapping"),
    Case(
        "duplicate key",
        yaml.safe_dump(GOOD, sort_keys=False) + "seed: 2\n",
        "duplicate key 'seed'",
    ),
    Case("binary file", b"\x00\xff\xfe garbage".decode("latin-1"), "exp.yaml"),
    # unknown keys at every level
    Case("unknown key at root", {**GOOD, "colour": "red"}, "colour: unknown key"),
    Case("unknown key terrain", with_("terrain.presett", "x"), "terrain.presett: unknown key"),
    Case(
        "unknown key light",
        with_("render.light.elevation_rad", 0.3),
        "render.light.elevation_rad: unknown key",
    ),
    Case(
        "unknown key camera",
        with_("render.camera", {"kind": "orthographic_nadir", "fov_deg": 30}),
        "render.camera.fov_deg: unknown key",
    ),
    Case("unknown key sensor", with_("render.sensor.iso", 100), "render.sensor.iso: unknown key"),
    Case("unknown key bsdf", with_("render.bsdf", {"kind": "lambert", "roughness": 1}), "render.bsdf.roughness: unknown"),
    Case("unknown key study", with_("study.strategy", ["grid"]), "study.strategy: unknown key"),
    Case("unknown key figures", with_("figures.dpi", 300), "figures.dpi: unknown key"),
    # wrong types
    Case("wrong type trials", with_("study.trials", "twenty"), "study.trials: Input should be"),
    Case("wrong type spp", with_("render.spp", [1, 2]), "render.spp: Input should be"),
    Case("wrong type seed", with_("seed", "abc"), "seed: Input should be"),
    Case("wrong type terrain", {**GOOD, "terrain": "aerial_1"}, "terrain: Input should be"),
    # NaN / inf / negative / zero where invalid
    Case("nan angle", with_("render.light.elevation_deg", float("nan")), "elevation_deg"),
    Case("inf spacing", dem_cfg(spacing_m=float("inf")), "terrain.spacing_m", setup=files(dem__npy=good_dem)),
    Case("negative spp", with_("render.spp", -1), "render.spp: Input should be greater"),
    Case("zero trials", with_("study.trials", 0), "study.trials: Input should be greater"),
    Case("negative spacing", dem_cfg(spacing_m=-0.2), "terrain.spacing_m", setup=files(dem__npy=good_dem)),
    Case("zero altitude", with_("render.camera.altitude_m", 0), "render.camera.altitude_m"),
    Case("negative noise", with_("render.sensor.read_noise_e", -1), "render.sensor.read_noise_e"),
    Case("zero scale", with_("terrain.scale", 0), "terrain.scale: Input should be greater"),
    # units
    Case("bad unit", with_("render.light.elevation_deg", "30 parsec"), "bad unit 'parsec'"),
    Case("unit without number", with_("render.light.elevation_deg", "deg"), "elevation_deg"),
    Case("length unit on angle", with_("render.light.azimuth_deg", "3 m"), "bad unit 'm'"),
    # names that select code
    Case("unknown preset", with_("terrain.preset", "aerial_9"), "unknown terrain preset"),
    Case("unknown strategy", with_("study.strategies", ["random", "wavelets"]), "study.strategies[1]: unknown strategy"),
    Case("unknown metric", with_("study.metrics", ["msee"]), "study.metrics[0]: unknown metric"),
    Case("unknown bsdf", with_("render.bsdf", {"kind": "phong"}), "render.bsdf: kind must be one of"),
    Case("unknown light", with_("render.light", {"kind": "laser"}), "render.light: kind must be one of"),
    Case("unknown camera", with_("render.camera", {"kind": "fisheye"}), "render.camera: kind must be one of"),
    Case("unknown study", with_("study.kind", "survey"), "study: kind must be one of"),
    # sweeps
    Case("sweep over a missing key", {**GOOD, "sweep": {"render.light.zenith_deg": [1, 2]}}, "sweep.render.light.zenith_deg: no such key"),
    Case("sweep empty list", {**GOOD, "sweep": {"render.spp": []}}, "sweep.render.spp: give at least one value"),
    Case("sweep bad last point", {**GOOD, "sweep": {"render.spp": [4, 8, 0]}}, "sweep.render.spp[2]"),
    Case("sweep not a list", {**GOOD, "sweep": {"render.spp": 4}}, "sweep.render.spp"),
    # densities
    Case("density above 1", with_("study.densities", [0.5, 1.5]), "study.densities[1]: a density must lie in (0, 1]"),
    Case("density zero", with_("study.densities", [0]), "study.densities[0]"),
    Case("densities empty", with_("study.densities", []), "study.densities"),
    Case("density below one sample", with_("study.densities", [0.5, 1e-7]), "study.densities[1]: density 1e-07 gives 0 samples"),
    # DEM and albedo files
    Case("missing DEM", dem_cfg(), "terrain.file: file not found"),
    Case("empty DEM", dem_cfg(), "terrain.file", setup=files(dem__npy=raw(b""))),
    Case("corrupt DEM", dem_cfg(), "terrain.file", setup=files(dem__npy=raw(b"\x93NUMPY garbage" * 10))),
    Case("all-NaN DEM", dem_cfg(), "every height is NaN", setup=files(dem__npy=lambda p: _npy(p, np.full((8, 8), np.nan)))),
    Case("1x1 DEM", dem_cfg(), "at least 2 x 2 cells, got 1 x 1", setup=files(dem__npy=lambda p: _npy(p, [[1.0]]))),
    Case("DEM of text", dem_cfg(), "terrain.file", setup=files(dem__npy=lambda p: _npy(p, np.array([["a", "b"], ["c", "d"]])))),
    Case("DEM mostly holes", dem_cfg(), f"of the heights are NaN (holes); at most {100 * MAX_NAN_FRACTION:g}%", setup=files(dem__npy=nan_dem(0.125))),
    Case("DEM heights 1e300", dem_cfg(), "heights reach 1e+300 m", setup=files(dem__npy=lambda p: _npy(p, _heights() + 1e300))),
    Case("DEM npz 2-element spacing", {**GOOD, "terrain": {"file": "dem.npz", "spacing_m": 0.2}}, "'spacing' must be one number", setup=files(dem__npz=npz(heights=_heights(), spacing=np.array([0.2, 0.2])))),
    Case("DEM npz without heights", {**GOOD, "terrain": {"file": "dem.npz", "spacing_m": 0.2}}, "no 'heights' array", setup=files(dem__npz=npz(z=_heights()))),
    Case("missing albedo", dem_cfg(albedo_file="alb.npy"), "terrain.albedo_file: file not found", setup=files(dem__npy=good_dem)),
    Case("empty albedo", dem_cfg(albedo_file="alb.npy"), "terrain.albedo_file", setup=files(dem__npy=good_dem, alb__npy=raw(b""))),
    Case("corrupt albedo", dem_cfg(albedo_file="alb.npy"), "terrain.albedo_file", setup=files(dem__npy=good_dem, alb__npy=raw(b"PK\x03\x04 not a zip"))),
    Case("all-NaN albedo", dem_cfg(albedo_file="alb.npy"), "albedo must be finite and within [0, 1]", setup=files(dem__npy=good_dem, alb__npy=lambda p: _npy(p, np.full((24, 32), np.nan)))),
    Case("1x1 albedo", dem_cfg(albedo_file="alb.npy"), "albedo shape 1 x 1 differs from the DEM's 24 x 32", setup=files(dem__npy=good_dem, alb__npy=lambda p: _npy(p, [[0.1]]))),
    Case("albedo .npy stack", dem_cfg(albedo_file="alb.npy"), "an albedo .npy must hold one (rows, cols) numeric grid", setup=files(dem__npy=good_dem, alb__npy=lambda p: _npy(p, np.full((2, 24, 32), 0.1)))),
    Case("albedo shape mismatch", dem_cfg(albedo_file="alb.npy"), "albedo shape 32 x 24 differs", setup=files(dem__npy=good_dem, alb__npy=lambda p: _npy(p, np.full((32, 24), 0.1)))),
    # geometry that sees nothing
    Case("camera at its target", with_("render.camera", {**PERSPECTIVE, "look_at_m": PERSPECTIVE["position_m"]}), "render.camera.look_at_m: equals position_m"),
    Case("camera looking away", with_("render.camera", {**PERSPECTIVE, "look_at_m": [20.0, -12.0, 60.0]}), "render.camera: the camera at [20.0, -12.0, 30.0] looking at [20.0, -12.0, 60.0] sees no terrain"),
    Case("camera beside the terrain", with_("render.camera", {**PERSPECTIVE, "position_m": [500.0, 0.0, 30.0], "look_at_m": [500.0, 0.0, 0.0]}), "sees no terrain"),
    Case("rover mast off the terrain", with_("render.camera", {"kind": "rover_mast", "site_m": [500.0, 0.0]}), "render.camera.site_m: [500, 0] m lies outside the terrain"),
    Case("rover mast density below one sample", {**with_("render.camera", {"kind": "rover_mast", "width": 32, "height": 24}), "study": {**GOOD["study"], "densities": [0.5, 0.003]}}, "density 0.003 gives 2 samples on the 24 x 32 image"),
    Case("camera far away", with_("render.camera", {**PERSPECTIVE, "position_m": [0.0, 0.0, 1e300]}), "render.camera.position_m: coordinates must be finite"),
    Case("scanner projector 0 x 0", with_("study", {**SCANNER, "projector_px": [0, 0]}), "study.projector_px"),
    Case("sweep point that sees nothing", {**with_("render.camera", PERSPECTIVE), "sweep": {"render.camera.look_at_m": [[20.0, -12.5, 0.0], [20.0, -12.0, 60.0]]}}, "sweep point 1 (look_at_m=[20.0, -12.0, 60.0]): render.camera"),
    # the output folder
    Case("out is a file", GOOD, "is a file, not a folder", setup=files(results=a_file)),
    Case("out below a file", GOOD, "is a file, so no folder can be made in it", setup=files(results=a_file), out="results/sub"),
    Case("out read-only", GOOD, "read-only filesystem", setup=files(results=read_only)),
    Case("out/units a file", GOOD, "units is not a folder", setup=lambda d: ((d / "results").mkdir(), (d / "results" / "units").write_text("x"))),
    Case("out holds other files", GOOD, "not a simlunar result folder", setup=lambda d: ((d / "results").mkdir(), (d / "results" / "notes.txt").write_text("mine"))),
    Case("out has a garbage config", GOOD, "config.yaml: not valid YAML", setup=lambda d: ((d / "results").mkdir(), (d / "results" / "config.yaml").write_text("{{{ not yaml"))),
    # options
    Case("bad --set", GOOD, "--set render.spp: expected key.path=value", args=("--set", "render.spp")),
    Case("--set unknown key", GOOD, "--set render.spq: no such key", args=("--set", "render.spq=3")),
    Case("--set bad yaml", GOOD, "--set render.spp: value is not valid YAML", args=("--set", "render.spp=[1,")),
    Case("--set bad value", GOOD, "render.spp: Input should be greater", args=("--set", "render.spp=0")),
    Case("--workers 0", GOOD, "--workers must be >= 1, got 0", args=("--workers", "0")),
    Case("--workers and --scheduler", GOOD, "either --workers or --scheduler", args=("--workers", "2", "--scheduler", "tcp://127.0.0.1:9")),
    Case("malformed --scheduler", GOOD, "--scheduler 'not a url': not a scheduler address", args=("--scheduler", "not a url")),
    Case("--scheduler port out of range", GOOD, "not a scheduler address", args=("--scheduler", "tcp://127.0.0.1:99999")),
    Case("unreachable --scheduler", GOOD, "--scheduler tcp://127.0.0.1:9: cannot connect", args=("--scheduler", "tcp://127.0.0.1:9")),
    # value checks and option models of the typed configuration
    Case("sun on the horizon", {**GOOD, "sweep": {"render.light.elevation_deg": [30, 60, 0]}}, "elevation_deg"),
    Case("sigma 90", with_("render.bsdf", {"kind": "oren_nayar", "sigma_deg": 90}), "sigma_deg"),
    Case("inf irradiance", with_("render.light.irradiance", float("inf")), "irradiance"),
    Case("inf full well", with_("render.sensor.full_well_e", float("inf")), "full_well_e"),
    Case("inf gamma", with_("render.sensor.gamma", float("inf")), "gamma"),
    Case("unknown scanner option", with_("study", {**SCANNER, "options": {"gray_opts": {"subpixle": True}}}), "subpixle"),
    Case("daylight scan without a sun", {**with_("study", {**SCANNER, "scan_light": "sun"}), "render": {**GOOD.get("render", {}), "light": {"kind": "camera"}}}, "study.scan_light: sun needs render.light.kind sun"),
    Case("sun guide light without a sun", {**with_("study", {**SCANNER, "guide_light": "sun"}), "render": {**GOOD.get("render", {}), "light": {"kind": "camera"}}}, "study.guide_light: sun needs render.light.kind sun"),
    Case("low_contrast without the gray code", with_("study", {**SCANNER, "modes": ["data_reduction"], "planners": ["low_contrast"]}), "planners: low_contrast ranks the pixels of the gray-code scan"),
    Case("options for low_contrast", with_("study", {**SCANNER, "planners": ["low_contrast"], "options": {"planner_opts": {"low_contrast": {"feature_opts": {"levels": 1}}}}}), "options.planner_opts.low_contrast: low_contrast takes no options"),
    Case("unknown scanner planner", with_("study", {**SCANNER, "planners": ["low_contrst"]}), "study.planners[0]: unknown planner 'low_contrst' (valid: combination, entropy, gradient, grid, low_contrast, random, saliency, wavelet)"),
    Case("unknown scan light", with_("study", {**SCANNER, "scan_light": "moon"}), "scan_light"),
    Case("unknown rig option", with_("study", {**SCANNER, "options": {"rig": {"tilt_deg": 3}}}), "tilt"),
    Case("unknown strategy option", with_("study.strategy_options", {"wavelet": {"blue_nose": True}}), "blue_nose"),
]  # fmt: skip


def tree_hash(root: Path) -> str:
    """SHA-256 over every path (relative) and file's bytes under ``root``."""
    h = hashlib.sha256()
    for p in sorted(root.rglob("*")):
        h.update(str(p.relative_to(root)).encode())
        if p.is_file():
            h.update(p.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def _run_case(case: Case, tmp_path: Path, monkeypatch) -> None:
    d = tmp_path / "case"
    d.mkdir()
    exp = d / "exp.yaml"
    text = case.data if isinstance(case.data, str) else yaml.safe_dump(case.data, sort_keys=False)
    exp.write_text(text, encoding="latin-1" if case.name == "binary file" else "utf-8")
    if case.setup is not None:
        case.setup(d)
    out = d / case.out
    if case.name == "out read-only":
        _make_read_only(d / "results", monkeypatch)
    existed = out.exists()
    before = tree_hash(d)
    monkeypatch.chdir(d)
    r = CliRunner().invoke(app, ["run", str(exp), "--out", str(out), "--no-progress", *case.args])
    assert r.exit_code == 2, (r.exit_code, r.output)
    assert r.stdout == "", r.stdout
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("error: "), lines[0]
    assert case.expect in lines[0], lines[0]
    assert "Traceback" not in r.output
    assert out.exists() == existed
    assert tree_hash(d) == before


def _make_read_only(folder: Path, monkeypatch) -> None:
    """A read-only folder: permissions for a normal user; root ignores permissions, so for
    root the folder's filesystem reports itself mounted read-only (``statvfs``)."""
    if os.geteuid() != 0:
        folder.chmod(0o555)
        return
    real = os.statvfs

    class _RO:
        def __init__(self, st):
            self.f_flag = st.f_flag | os.ST_RDONLY

    def statvfs(path):
        st = real(path)
        return _RO(st) if Path(path).resolve().is_relative_to(folder.resolve()) else st

    monkeypatch.setattr(os, "statvfs", statvfs)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(case, tmp_path, monkeypatch):
    _run_case(case, tmp_path, monkeypatch)


def test_there_are_at_least_40_distinct_cases():
    names = [c.name for c in CASES]
    assert len(set(names)) == len(names) >= 40


def test_the_good_config_passes_the_checks(tmp_path):
    """The cases above differ from a config that is valid (so each fails for its own reason)."""
    from simlunar.config.loading import validate_data
    from simlunar.pipeline.preflight import check_units
    from simlunar.pipeline.runner import expand

    _npy(tmp_path / "dem.npy", _heights())
    _npy(tmp_path / "alb.npy", np.full((24, 32), 0.1))
    for data in (
        GOOD,
        dem_cfg(albedo_file="alb.npy"),
        with_("render.camera", PERSPECTIVE),
        {**with_("render.camera", PERSPECTIVE), "sweep": {"render.spp": [4, 8]}},
        with_("study", SCANNER),
    ):
        cfg = validate_data(data, base_dir=tmp_path)
        check_units(expand(cfg))
    # just under the hole threshold is accepted (and reported)
    nan_dem(MAX_NAN_FRACTION * 0.9)(tmp_path / "dem.npy")
    facts = check_units(expand(validate_data(dem_cfg(), base_dir=tmp_path)))
    assert 0 < facts.holes()[0]["nan_fraction"] <= MAX_NAN_FRACTION
