"""`simlunar run` on bad input: every case exits 2 with one line on stderr and writes nothing.

Each case is run in-process through the Typer CLI. The check is strict: exit code 2, stdout
empty, exactly one stderr line starting ``error: `` and containing the expected words, no
traceback, and the SHA-256 of the whole test folder (the YAML, the input files, the output
folder when it exists beforehand) unchanged, so nothing was written anywhere. Almost every
case must fail in validation or in the preflight checks, before any render: the test module
runs in seconds.
"""

from __future__ import annotations

import functools
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
from simlunar.pipeline.inputs import MAX_NAN_FRACTION

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
SCAN_DOTS = {**SCANNER, "modes": ["ambiguity_enhancement"]}
#: nine levels of ten aliases each: 10^9 values from a few lines
ALIAS_BOMB = "name: x\nl0: &l0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n" + "".join(
    f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * 10)}]\n" for i in range(1, 9)
)


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


def npy_header(shape):
    """A .npy file whose header promises a float64 array of ``shape`` and holds 100 bytes."""

    def write(p: Path) -> None:
        import io

        from numpy.lib import format as npf

        head = io.BytesIO()
        npf.write_array_header_1_0(
            head, {"descr": "<f8", "fortran_order": False, "shape": tuple(shape)}
        )
        p.write_bytes(head.getvalue() + bytes(100))

    return write


def npz_header(shape):
    def write(p: Path) -> None:
        import zipfile

        tmp = p.with_suffix(".part.npy")
        npy_header(shape)(tmp)
        with zipfile.ZipFile(p, "w") as z:
            z.write(tmp, "heights.npy")
        tmp.unlink()

    return write


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
    env: dict = field(default_factory=dict)


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
    Case("refine_m on a preset", with_("terrain.refine_m", 0.1), "refine_m: goes with a DEM file (terrain.file)"),
    Case("rocks on a preset", with_("terrain.rocks", {"law": "golombek", "coefficient": 0.07}), "rocks: goes with a DEM file (terrain.file)"),
    Case("DEM refined coarser", dem_cfg(refine_m=0.5), "terrain.refine_m: 0.5 m is coarser than the DEM's 0.2 m cells", setup=files(dem__npy=lambda p: _npy(p, np.zeros((8, 8))))),
    Case("DEM refined past the cell limit", dem_cfg(refine_m=1e-4), "dem.npy refined to 0.0001 m: 16000 x 16000 cells = 2.56e+08, more than the limit", setup=files(dem__npy=lambda p: _npy(p, np.zeros((8, 8))))),
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
    Case("unknown scanner planner", with_("study", {**SCANNER, "planners": ["low_contrst"]}), "study.planners[0]: unknown planner 'low_contrst' (valid: combination, entropy, gradient, grid, learned, lloyd_uniform, log_energy, log_lloyd, low_contrast, random, saliency, wavelet, wavelet_lloyd)"),
    Case("unknown scan light", with_("study", {**SCANNER, "scan_light": "moon"}), "scan_light"),
    Case("unknown rig option", with_("study", {**SCANNER, "options": {"rig": {"tilt_deg": 3}}}), "tilt"),
    Case("unknown strategy option", with_("study.strategy_options", {"wavelet": {"blue_nose": True}}), "blue_nose"),
    # scanner options checked with the library's rules before anything runs
    Case("scanner metric unknown", with_("study", {**SCANNER, "metrics": ["msee"]}), "study.metrics[0]: unknown metric 'msee'"),
    Case("scanner planners twice", with_("study", {**SCAN_DOTS, "planners": ["random", "random"]}), "study.planners: names must be unique"),
    Case("scanner metrics twice", with_("study", {**SCANNER, "metrics": ["mse", "mse"]}), "study.metrics: names must be unique"),
    Case("scanner modes twice", with_("study", {**SCANNER, "modes": ["gray_code", "gray_code"]}), "study.modes: names must be unique"),
    Case("dot budget below 3 on the projector", with_("study", {**SCAN_DOTS, "budget": 0.001, "projector_px": [32, 24], "camera_px": [256, 192]}), "study.budget: 0.001 of the 32 x 24 projector gives 1 dots for planner random"),
    Case("projector spacing 0", with_("study", {**SCAN_DOTS, "options": {"dot_opts": {"min_proj_spacing_px": 0}}}), "min_proj_spacing_px: scheduling spacings must be > 0 px"),
    Case("camera spacing 0", with_("study", {**SCAN_DOTS, "options": {"dot_opts": {"min_cam_spacing_px": 0}}}), "min_cam_spacing_px: scheduling spacings must be > 0 px"),
    Case("scanner entropy window even", with_("study", {**SCAN_DOTS, "planners": ["entropy"], "options": {"planner_opts": {"entropy": {"feature_opts": {"size": 8}}}}}), "entropy window size must be odd, 1..63, got 8"),
    Case("sampling entropy window huge", with_("study.strategy_options", {"entropy": {"feature_opts": {"size": 100001}}}), "entropy window size must be odd, 1..63, got 100001"),
    Case("sampling entropy window even", with_("study.strategy_options", {"entropy": {"feature_opts": {"size": 10}}}), "feature_opts.size"),
    Case("scanner combination without coefficients", with_("study", {**SCAN_DOTS, "planners": ["combination"]}), "planners (combination).coefficients: strategy 'combination' needs at least one weight"),
    Case("sampling combination without coefficients", with_("study.strategies", ["random", "combination"]), "strategies (combination).coefficients"),
    Case("sparse_spp without a maximum", with_("study", {**SCAN_DOTS, "options": {"capture_opts": {"sparse_spp": 10**9}}}), "sparse_spp: Input should be less than or equal to 4096"),
    Case("dot px with a length unit", with_("study", {**SCAN_DOTS, "options": {"dot_opts": {"tol_px": "1 m"}}}), "bad unit 'm' for a _px key"),
    Case("projector px not whole", with_("study", {**SCANNER, "projector_px": ["64.5 px", 48]}), "whole number of pixels"),
    Case("rig zero baseline", with_("study", {**SCANNER, "options": {"rig": {"baseline_m": 1e-12}}}), "study.options.rig: baseline is zero"),
    Case("rig camera not seeing the pattern", with_("study", {**SCANNER, "options": {"rig": {"verge": False, "baseline_m": 5000}}}), "study.options.rig: the camera at"),
    Case("scanner sweep point with a bad rig", {**with_("study", SCANNER), "sweep": {"study.options.rig.baseline_m": [1.0, 1e-12]}}, "sweep point 1 (baseline_m=1e-12): study.options.rig: baseline is zero"),
    # sizes, with the limits lowered so that a regression allocates little (the enormous
    # sizes themselves: test_enormous_sizes_are_refused_under_a_memory_limit)
    Case("terrain cells above the limit", GOOD, "terrain.preset: 125 x 200 cells = 2.5e+04, more than the limit of 1e+03 (set SIMLUNAR_MAX_CELLS", env={"SIMLUNAR_MAX_CELLS": "1000"}),
    Case("grid override above the limit", with_("terrain", {"preset": "aerial_1", "overrides": {"grid": {"rows": 400, "cols": 400}}}), "terrain.overrides.grid: 400 x 400 cells", env={"SIMLUNAR_MAX_CELLS": "100000"}),
    Case("DEM cells above the limit", dem_cfg(), "terrain.file: ", setup=files(dem__npy=good_dem), env={"SIMLUNAR_MAX_CELLS": "100"}),
    Case("perspective image above the limit", with_("render.camera", {**PERSPECTIVE, "width": 320, "height": 240}), "render.camera: a 240 x 320 image = 7.68e+04, more than the limit", env={"SIMLUNAR_MAX_CELLS": "30000"}),
    Case("projector above the limit", with_("study", {**SCANNER, "projector_px": [400, 300]}), "study.projector_px: 400 x 300 pixels", env={"SIMLUNAR_MAX_CELLS": "100000"}),
    Case("camera above the limit", with_("study", {**SCANNER, "projector_px": [40, 30], "camera_px": [400, 300]}), "study.camera_px: 400 x 300 pixels", env={"SIMLUNAR_MAX_CELLS": "100000"}),
    Case("gray-code frames x pixels above the limit", with_("study", SCANNER), "gray-code frames x", env={"SIMLUNAR_MAX_FRAME_PIXELS": "100000"}),
    # transient films: receiver pixels x time bins x channels, before any render
    Case("lidar time bins above the limit", with_("study", {"kind": "lidar", "sensor": "flash", "planners": ["random"], "densities": ["1/64"], "options": {"bin_range_m": 1e-5, "flash": {"receiver_px": [32, 24]}}}, with_("render.camera", PERSPECTIVE)), "study.options.bin_range_m: 32 x 24 receiver pixels x "),
    Case("steered-beam batch x time bins above the limit", with_("study", {"kind": "lidar", "sensor": "steered_beam", "planners": ["random"], "densities": ["1/64"], "options": {"steered_beam": {"batch": 4096, "window_m": 8}}}, with_("render.camera", PERSPECTIVE)), "study.options.bin_range_m: 4096 beams x 160 time bins x 4 channels", env={"SIMLUNAR_MAX_FRAME_PIXELS": "1000000"}),
    Case("dot batch x pixels above the limit", with_("study", {**SCAN_DOTS, "options": {"dot_opts": {"batch": 100000}}}), "study.options.dot_opts.batch: 100000 frames x"),
    Case("limit setting not a number", GOOD, "SIMLUNAR_MAX_CELLS=lots: expected a positive count", env={"SIMLUNAR_MAX_CELLS": "lots"}),
    Case("DEM header promises more than the file", dem_cfg(), "its header promises a 300 x 400 array (960000 bytes) but the file holds", setup=files(dem__npy=npy_header((300, 400)))),
    Case("albedo header promises more than the file", dem_cfg(albedo_file="alb.npy"), "terrain.albedo_file: ", setup=files(dem__npy=good_dem, alb__npy=npy_header((24, 32)))),
    Case("DEM npz header promises more than the file", {**GOOD, "terrain": {"file": "dem.npz", "spacing_m": 0.2}}, "(heights): its header promises", setup=files(dem__npz=npz_header((300, 400)))),
    # YAML
    Case("alias bomb", ALIAS_BOMB, "aliases expand to more than 1,000,000 values"),
    Case("recursive alias", "name: x\nseed: &a [1, *a]\n", "recursive alias"),
    Case("merge key with a duplicate explicit key", "base: &b {preset: aerial_1}\nname: x\nterrain: {<<: *b, scale: 0.1, scale: 0.2}\n", "duplicate key 'scale'"),
    Case("merge key of a scalar", "name: x\nterrain: {<<: 3}\n", "exp.yaml"),
    # the renderer asked for by the environment
    Case("unknown SIMLUNAR_VARIANT", GOOD, "SIMLUNAR_VARIANT=rgb_fast: unknown variant 'rgb_fast'", env={"SIMLUNAR_VARIANT": "rgb_fast"}),
    # a finished folder whose scans is a file: refused before anything is deleted
    Case("--save-scans with scans a file", with_("study", SCANNER), "scans is not a folder", args=("--save-scans",), setup=lambda d: ((d / "results").mkdir(), (d / "results" / "config.yaml").write_text("x: 1\n"), (d / "results" / "results.csv").write_text("unit\n"), (d / "results" / "scans").write_text("a file"))),
    # a learned map whose model file was never trained: once found only after the render, as
    # an internal error; now an input of the unit, checked (and hashed) before any work
    Case("learned model file missing", with_("study.strategy_options", {"l": {"strategy": "learned", "placement": "lloyd", "feature_opts": {"model": "models/none.joblib"}}}, with_("study.strategies", ["random", "l"])), "study.strategy_options.l.feature_opts.model: cannot read models/none.joblib (No such file or directory) (a learned model: make it with `simlunar train"),
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
    for k, v in case.env.items():
        monkeypatch.setenv(k, v)
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


@pytest.mark.parametrize(
    "case", [pytest.param(c, marks=c.marks) for c in CASES], ids=[c.name for c in CASES]
)
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


# --------------------------------------------------------------------------- every subcommand
# The entry point itself (``simlunar.cli.main``, as the ``simlunar`` script runs it, and
# ``python -m simlunar.pipeline.fit``), so usage errors are checked as the user sees them.
SCENE = {
    "name": "bad_scene",
    "terrain": {"preset": "aerial_1", "scale": 0.125},
    "render": {"spp": 2},
}


def yaml_file(name: str, data):
    def write(d: Path) -> None:
        text = data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False)
        (d / name).write_text(text)

    return write


def side_json(spacing):
    def write(d: Path) -> None:
        good_dem(d / "dem.npy")
        (d / "dem.npy.json").write_text(f'{{"spacing": {spacing}}}')

    return write


def dem_file(writer, name="dem.npy"):
    return lambda d: writer(d / name)


def both(*setups):
    def setup(d: Path) -> None:
        for s in setups:
            s(d)

    return setup


@dataclass
class Cmd:
    name: str
    argv: tuple[str, ...]
    expect: str
    code: int = 2
    setup: Callable[[Path], None] | None = None
    env: dict = field(default_factory=dict)
    marks: list = field(default_factory=list)


CMDS = [
    # usage errors: one line, not click's box
    Cmd("--workers abc", ("run", "exp.yaml", "--workers", "abc"), "simlunar run: Invalid value for '--workers'", setup=yaml_file("exp.yaml", GOOD)),
    Cmd("run without its argument", ("run",), "simlunar run: Missing argument"),
    Cmd("misspelt command", ("runn", "exp.yaml"), "No such command 'runn'"),
    Cmd("unknown option", ("run", "exp.yaml", "--wrokers", "2"), "No such option"),
    Cmd("missing experiment file", ("run", "nope.yaml"), "experiment file not found: nope.yaml"),
    # terrain
    Cmd("terrain --seed -1", ("terrain", "aerial_1", "--out", "t", "--seed", "-1"), "--seed must be >= 0, got -1"),
    Cmd("terrain --scale 2", ("terrain", "aerial_1", "--out", "t", "--scale", "2"), "--scale must lie in (0, 1]"),
    Cmd("terrain --scale abc", ("terrain", "aerial_1", "--out", "t", "--scale", "abc"), "Invalid value for '--scale'"),
    Cmd("terrain --mesh stl", ("terrain", "aerial_1", "--out", "t", "--mesh", "stl"), "--mesh must be ply, obj or none"),
    Cmd("terrain --format png", ("terrain", "aerial_1", "--out", "t", "--format", "png"), "--format must be exr, npz, npy or tif"),
    Cmd("terrain without --out", ("terrain", "aerial_1"), "--out is required"),
    Cmd("terrain unknown preset", ("terrain", "aerial_9", "--out", "t"), "aerial_9"),
    Cmd("terrain --out a file", ("terrain", "aerial_1", "--out", "t", "--scale", "0.125"), "--out t: is a file, not a folder", setup=lambda d: (d / "t").write_text("x")),
    Cmd("terrain --stats absurd sidecar spacing", ("terrain", "dem.npy", "--stats"), "--stats: the terrain reaches", setup=side_json("1e308")),
    Cmd("terrain --stats zero sidecar spacing", ("terrain", "dem.npy", "--stats"), "spacing", setup=side_json("0")),
    Cmd("terrain --stats header promises more", ("terrain", "dem.npy", "--stats"), "its header promises a 300 x 400 array", setup=dem_file(npy_header((300, 400)))),
    Cmd("terrain --stats DEM above the limit", ("terrain", "dem.npy", "--stats"), "more than the limit of 100", setup=side_json("0.2"), env={"SIMLUNAR_MAX_CELLS": "100"}),
    Cmd("terrain --stats all-NaN DEM", ("terrain", "dem.npy", "--stats"), "every height is NaN", setup=both(dem_file(lambda p: _npy(p, np.full((8, 8), np.nan))), lambda d: (d / "dem.npy.json").write_text('{"spacing": 1}'))),
    Cmd("terrain --stats bad features.json", ("terrain", "dem.npy", "--stats"), "features.json: not valid JSON", setup=both(side_json("0.2"), lambda d: (d / "features.json").write_text("{"))),
    # schema
    Cmd("schema --out a folder", ("schema", "--out", "s"), "--out s: is a folder, not a file", setup=lambda d: (d / "s").mkdir()),
    Cmd("schema --out below a file", ("schema", "--out", "f/s.json"), "--out f/s.json: f: is a file, not a folder", setup=lambda d: (d / "f").write_text("x")),
    Cmd("schema --kind bogus", ("schema", "--kind", "bogus"), "--kind bogus: unknown document kind"),
    # figures
    Cmd("figures of a missing folder", ("figures", "nope"), "nope: no such folder"),
    Cmd("figures of a file", ("figures", "f"), "is a file, not a folder", setup=lambda d: (d / "f").write_text("x")),
    # render
    Cmd("render missing scene", ("render", "nope.yaml", "--out", "r"), "nope.yaml"),
    Cmd("render scene above the size limit", ("render", "scene.yaml", "--out", "r"), "terrain.overrides.grid: 400 x 400 cells", setup=yaml_file("scene.yaml", {**SCENE, "terrain": {"preset": "aerial_1", "overrides": {"grid": {"rows": 400, "cols": 400}}}}), env={"SIMLUNAR_MAX_CELLS": "100000"}),
    Cmd("render --out a file", ("render", "scene.yaml", "--out", "r"), "--out r: is a file", setup=both(yaml_file("scene.yaml", SCENE), lambda d: (d / "r").write_text("x"))),
    Cmd("render unknown SIMLUNAR_VARIANT", ("render", "scene.yaml", "--out", "r"), "SIMLUNAR_VARIANT=rgb_fast: unknown variant", setup=yaml_file("scene.yaml", SCENE), env={"SIMLUNAR_VARIANT": "rgb_fast"}),
    Cmd("render merge-key duplicate", ("render", "scene.yaml", "--out", "r"), "duplicate key 'scale'", setup=yaml_file("scene.yaml", "b: &b {preset: aerial_1}\nname: s\nterrain: {<<: *b, scale: 0.1, scale: 0.2}\n")),
    # doctor
    Cmd("doctor unknown SIMLUNAR_VARIANT", ("doctor", "--short"), "SIMLUNAR_VARIANT=rgb_fast: unknown variant", env={"SIMLUNAR_VARIANT": "rgb_fast"}),
    Cmd("doctor CUDA without a GPU", ("doctor",), "SIMLUNAR_VARIANT=cuda_ad_rgb: cuda_ad_rgb requested but unusable", code=3, env={"SIMLUNAR_VARIANT": "cuda_ad_rgb"}, marks=[pytest.mark.skipif(Path("/dev/nvidia0").exists(), reason="a GPU is present")]),
    # fit (python -m simlunar.pipeline.fit)
    Cmd("fit --maxiter -5", ("fit", "res", "--train-seeds", "1", "--test-seeds", "2", "--maxiter", "-5"), "--maxiter must be an integer >= 1, got -5"),
    Cmd("fit --trials 0", ("fit", "res", "--train-seeds", "1", "--test-seeds", "2", "--trials", "0"), "--trials must be an integer >= 1, got 0"),
    Cmd("fit --restarts -1", ("fit", "res", "--train-seeds", "1", "--test-seeds", "2", "--restarts", "-1"), "--restarts must be an integer >= 0"),
    Cmd("fit --maxiter abc", ("fit", "res", "--train-seeds", "1", "--test-seeds", "2", "--maxiter", "abc"), "argument --maxiter: invalid int value: 'abc'"),
    Cmd("fit without seeds", ("fit", "res"), "the following arguments are required"),
    Cmd("fit of a missing folder", ("fit", "nope", "--train-seeds", "1", "--test-seeds", "2"), "nope"),
]  # fmt: skip


def _raise_exit(code: int):
    raise SystemExit(code)


def _main(argv, monkeypatch) -> int:
    """Exit code of ``simlunar <argv>`` (or the fit command) run in this process."""
    import signal
    import sys

    if argv[0] == "fit":
        from simlunar.pipeline.fit import main as fit_main

        try:
            return fit_main(list(argv[1:]))
        except SystemExit as exc:  # argparse's usage errors
            return int(exc.code)
    from simlunar.cli import main

    monkeypatch.setattr(sys, "argv", ["simlunar", *argv])
    handler = signal.getsignal(signal.SIGINT)
    try:
        main()
    except SystemExit as exc:
        return int(exc.code or 0)
    finally:
        signal.signal(signal.SIGINT, handler)  # main() routes Ctrl-C through its flag
    return 0


@pytest.mark.parametrize(
    "case", [pytest.param(c, marks=c.marks) for c in CMDS], ids=[c.name for c in CMDS]
)
def test_every_subcommand_keeps_the_promise(case, tmp_path, monkeypatch, capsys):
    # an environment failure (exit 3) leaves through os._exit, which would end pytest
    monkeypatch.setattr(os, "_exit", _raise_exit)
    d = tmp_path / "case"
    d.mkdir()
    if case.setup is not None:
        case.setup(d)
    for k, v in case.env.items():
        monkeypatch.setenv(k, v)
    before = tree_hash(d)
    monkeypatch.chdir(d)
    code = _main(case.argv, monkeypatch)
    out, err = capsys.readouterr()
    assert code == case.code, (code, out, err)
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: "), lines[0]
    assert case.expect in lines[0], lines[0]
    assert "Traceback" not in out + err and out == ""
    assert tree_hash(d) == before


def test_there_are_at_least_40_new_cases_across_subcommands():
    assert len(CMDS) + len(CASES) >= 89 + 40
    assert len({c.name for c in CMDS}) == len(CMDS)


# --------------------------------------------------------------------------- enormous sizes
ENORMOUS = {
    "grid override": (with_("terrain", {"preset": "aerial_1", "overrides": {"grid": {"rows": 50000, "cols": 50000}}}), None, "terrain.overrides.grid: 50000 x 50000 cells"),
    "projector": (with_("study", {**SCANNER, "projector_px": [100000, 100000]}), None, "study.projector_px: 100000 x 100000 pixels"),
    "camera": (with_("study", {**SCANNER, "camera_px": [100000, 100000]}), None, "study.camera_px: 100000 x 100000 pixels"),
    ".npy header": (dem_cfg(), npy_header((200000, 200000)), "a 200000 x 200000 array = 4e+10, more than the limit"),
}  # fmt: skip


@pytest.mark.parametrize("name", list(ENORMOUS))
def test_enormous_sizes_are_refused_under_a_memory_limit(name, tmp_path):
    """Refused before allocating: the CLI runs with a 3 GB address space, so a regression
    fails with a MemoryError here instead of taking the machine's memory."""
    import resource
    import subprocess
    import sys

    data, writer, expect = ENORMOUS[name]
    exp = tmp_path / "exp.yaml"
    exp.write_text(yaml.safe_dump(data, sort_keys=False))
    if writer is not None:
        writer(tmp_path / "dem.npy")

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))

    r = subprocess.run(
        [sys.executable, "-m", "simlunar.cli", "run", str(exp), "--out", str(tmp_path / "o"), "--no-progress"],
        capture_output=True, text=True, timeout=300, preexec_fn=limit, cwd=tmp_path,
    )  # fmt: skip
    assert r.returncode == 2, r.stderr
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and expect in lines[0], r.stderr
    assert not (tmp_path / "o").exists()


# --------------------------------------------------------------------------- faults and inputs
# Each class of bad input found by the fault audit: learned model files, training outputs,
# LIDAR options, structured-light rigs, sizes, YAML bombs, the environment. Every case: one
# stderr line, its exit code, and the case folder unchanged.
MODEL = "models/m.joblib"
LEARNED = with_(
    "study.strategy_options",
    {"l": {"strategy": "learned", "placement": "lloyd", "feature_opts": {"model": MODEL}}},
    with_("study.strategies", ["random", "l"]),
)


@functools.lru_cache(maxsize=1)
def _model_bytes() -> tuple[bytes, dict]:
    """A real tiny model (trained in about a second): its joblib bytes and its record."""
    import json
    import tempfile

    from scipy import ndimage

    from simlunar.features.learned import LearnedOptions
    from simlunar.planner.learning import train_learned_map

    gen = np.random.default_rng(7)
    pairs = []
    for _ in range(2):
        z = ndimage.gaussian_filter(gen.standard_normal((48, 64)), 3) * 5
        img = np.clip(0.5 + ndimage.gaussian_filter(gen.standard_normal((48, 64)), 1), 0.01, 1)
        pairs.append((img, z))
    model = train_learned_map(
        pairs, densities=[1 / 16], options=LearnedOptions(pixels_per_example=500, max_iter=5), rng=0
    )
    with tempfile.TemporaryDirectory() as tmp:
        path, record = model.save(Path(tmp) / "m.joblib")
        return path.read_bytes(), json.loads(record.read_text())


class _Boom:
    """Unpickling this writes a file: a case whose folder stays unchanged was never unpickled."""

    def __reduce__(self):
        return (open, ("UNPICKLED", "w"))


def model_files(data=None, record=None, *, edit=None, rehash=False, raw_record=None):
    """A setup writing ``models/m.joblib`` (``data``: bytes or a callable of the good bytes)
    and ``models/m.json`` (the good record, ``edit``-ed, or ``raw_record`` text); ``rehash``:
    the record's hash made to match the written bytes (a forged but consistent record)."""
    import hashlib
    import json

    def setup(d: Path) -> None:
        good, meta = _model_bytes()
        body = good if data is None else (data(good) if callable(data) else data)
        meta = dict(meta if record in (None, "missing") else record)
        if edit is not None:
            edit(meta)
        if rehash:
            meta["model_sha256"] = hashlib.sha256(body).hexdigest()
        (d / "models").mkdir(exist_ok=True)
        (d / MODEL).write_bytes(body)
        rec = d / "models" / "m.json"
        if raw_record is not None:
            rec.write_bytes(raw_record if isinstance(raw_record, bytes) else raw_record.encode())
        elif record != "missing":
            rec.write_text(json.dumps(meta))

    return setup


def _set(key, value):
    def edit(meta):
        cur = meta
        *head, last = key.split(".")
        for k in head:
            cur[k] = dict(cur[k])
            cur = cur[k]
        cur[last] = value

    return edit


MODEL_KEY = "study.strategy_options.l.feature_opts.model: "
FAULT_CASES = [
    # learned model files: refused in one line before any render, never unpickled unverified
    Case("model truncated", LEARNED, MODEL_KEY + "models/m.joblib: SHA-256 does not match its record", setup=model_files(lambda b: b[: len(b) // 2])),
    Case("model empty", LEARNED, "models/m.joblib: SHA-256 does not match its record", setup=model_files(b"")),
    Case("model a random pickle", LEARNED, "models/m.joblib: SHA-256 does not match its record", setup=model_files(lambda b: __import__("pickle").dumps(_Boom()))),
    Case("model a renamed text file", LEARNED, "models/m.joblib: SHA-256 does not match its record", setup=model_files(b"name: not a model\n")),
    Case("model forged record for a hostile pickle", LEARNED, "models/m.joblib: SHA-256 does not match", setup=model_files(lambda b: __import__("pickle").dumps(_Boom()), edit=_set("model_sha256", "0" * 64))),
    Case("model consistent record, foreign payload", LEARNED, "models/m.joblib: not a simlunar-learned-map/1 model file", setup=model_files(lambda b: __import__("pickle").dumps({"models": [1, 2]}), rehash=True)),
    Case("model consistent record, payload not regressors", LEARNED, "is not a regressor of the", setup=model_files(lambda b: __import__("pickle").dumps({"format": "simlunar-learned-map/1", "models": {"0.0625": "x"}}), rehash=True)),
    Case("model other feature set", LEARNED, "trained on feature set version 0, this simlunar computes", setup=model_files(edit=_set("feature_set_version", 0))),
    Case("model other feature names", LEARNED, "retrain the model", setup=model_files(edit=_set("feature_names", ["a", "b"]))),
    Case("model other scikit-learn", LEARNED, "saved with scikit-learn 0.1, installed", setup=model_files(edit=_set("versions.scikit-learn", "0.1"))),
    Case("model other format", LEARNED, "not a simlunar-learned-map/1 model (format 'x/9')", setup=model_files(edit=_set("format", "x/9"))),
    Case("model record not JSON", LEARNED, "models/m.json: not a JSON model record", setup=model_files(raw_record="{densities: [")),
    Case("model record a JSON list", LEARNED, "models/m.json: not a model record (a JSON list)", setup=model_files(raw_record="[1, 2]")),
    Case("model record binary", LEARNED, "models/m.json: not a JSON model record", setup=model_files(raw_record=b"\xff\xfe{\x00")),
    Case("model record other densities", LEARNED, "models/m.joblib: densities [0.0625] differ from its record's [0.5]", setup=model_files(edit=_set("densities", [0.5]))),
    Case("model record densities not numbers", LEARNED, "'densities' must list distinct sample fractions in (0, 1], got 'all'", setup=model_files(edit=_set("densities", "all"))),
    Case("model record density above 1", LEARNED, "'densities' must list distinct sample fractions", setup=model_files(edit=_set("densities", [2.0]))),
    Case("model record densities repeated", LEARNED, "'densities' must list distinct", setup=model_files(edit=_set("densities", [0.0625, 0.0625]))),
    Case("model record missing", LEARNED, "cannot read models/m.json", setup=model_files(record="missing")),
    Case("model record empty", LEARNED, "models/m.json: not a JSON model record", setup=model_files(raw_record="")),
]  # fmt: skip


@pytest.mark.parametrize("case", FAULT_CASES, ids=[c.name for c in FAULT_CASES])
def test_fault_case_exits_2_with_one_line_and_writes_nothing(case, tmp_path, monkeypatch):
    _run_case(case, tmp_path, monkeypatch)
    assert not (tmp_path / "case" / "UNPICKLED").exists()


def test_the_good_model_passes_the_checks(tmp_path, monkeypatch):
    """The model cases differ from a model that loads (each fails for its own reason)."""
    from simlunar.config.loading import validate_data
    from simlunar.pipeline.preflight import check_units
    from simlunar.pipeline.runner import expand

    model_files()(tmp_path)
    monkeypatch.chdir(tmp_path)
    check_units(expand(validate_data(LEARNED, base_dir=tmp_path)))


def training(**over):
    """A setup writing a valid training YAML (``train.yaml``) over the good experiment."""
    data = {
        "name": "t",
        "seed": 100,
        "experiments": ["exp.yaml"],
        "scale": 0.25,
        "terrain_seeds": 1,
        "sun_elevations_deg": [30],
        "densities": ["1/16"],
        "options": {"layouts": 1, "pixels_per_example": 500, "max_iter": 5},
        "model": "models/t.joblib",
        **over,
    }
    return both(yaml_file("exp.yaml", GOOD), yaml_file("train.yaml", data))


ROOT_IGNORES_PERMISSIONS = pytest.mark.skipif(
    os.geteuid() == 0, reason="root writes into read-only folders"
)


def read_only_dir(name):
    def setup(d: Path) -> None:
        (d / name).mkdir()
        (d / name).chmod(0o555)

    return setup


FAULT_CMDS = [
    # simlunar train: the output checked before minutes of rendering; suns above the horizon
    Cmd("train --out a folder", ("train", "train.yaml", "--out", "m.joblib"), "--out m.joblib: is a folder, not a file", setup=both(training(), lambda d: (d / "m.joblib").mkdir())),
    Cmd("train --out below a file", ("train", "train.yaml", "--out", "f/m.joblib"), "--out f/m.joblib: f: is a file, not a folder", setup=both(training(), lambda d: (d / "f").write_text("x"))),
    Cmd("train --out in a read-only folder", ("train", "train.yaml", "--out", "ro/m.joblib"), "ro is not writable (permission denied)", setup=both(training(), read_only_dir("ro")), marks=[ROOT_IGNORES_PERMISSIONS]),
    Cmd("train --out record is a folder", ("train", "train.yaml", "--out", "m.joblib"), "--out m.json: is a folder, not a file", setup=both(training(), lambda d: (d / "m.json").mkdir())),
    Cmd("train model below a file", ("train", "train.yaml"), "model models/t.joblib: models: is a file, not a folder", setup=both(training(), lambda d: (d / "models").write_text("x"))),
    Cmd("train --out not joblib", ("train", "train.yaml", "--out", "m.pkl"), "--out m.pkl: a learned model file ends in .joblib", setup=training()),
    Cmd("train sun at 0 deg", ("train", "train.yaml"), "sun_elevations_deg[0]: Input should be greater than 0", setup=training(sun_elevations_deg=[0])),
    Cmd("train sun at -45 deg", ("train", "train.yaml"), "sun_elevations_deg[1]: Input should be greater than 0", setup=training(sun_elevations_deg=[30, -45])),
    Cmd("train sun above the zenith", ("train", "train.yaml"), "Input should be less than or equal to 90", setup=training(sun_elevations_deg=[120])),
]  # fmt: skip


@pytest.mark.parametrize(
    "case", [pytest.param(c, marks=c.marks) for c in FAULT_CMDS], ids=[c.name for c in FAULT_CMDS]
)
def test_fault_command_keeps_the_promise(case, tmp_path, monkeypatch, capsys):
    test_every_subcommand_keeps_the_promise(case, tmp_path, monkeypatch, capsys)


# LIDAR options: the library's rules and every size bounded, in the schema
LIDAR = {"kind": "lidar", "planners": ["random"], "densities": ["1/64"], "trials": 1}
LIDAR_GOOD = with_("study", LIDAR, with_("render.camera", PERSPECTIVE))


def lidar(key: str, value) -> dict:
    return with_(f"study.{key}", value, LIDAR_GOOD)


LIDAR_CASES = [
    Case("lidar margin 5 m in the default 8 m window", lidar("options.margin_m", 5), "study.options.margin_m: 5 m leaves no range in the 8 m window of a rendered batch (steered_beam.window_m must exceed 2 x margin_m = 10 m)"),
    Case("lidar margin equal to half the window", lidar("options.steered_beam.window_m", 4), "steered_beam.window_m must exceed 2 x margin_m = 4 m"),
    Case("lidar divergence above pi/2", lidar("options.steered_beam.divergence_mrad", 2000), "study.options.steered_beam.divergence_mrad: Input should be less than 1570.79"),
    Case("lidar signal photons 1e30", lidar("options.detector.expert_signal_photons", 1e30), "study.options.detector.expert_signal_photons: Input should be less than or equal to 1000000000000"),
    Case("lidar background 1e30 photons/s", lidar("options.detector.expert_background_photons_per_s", 1e30), "study.options.detector.expert_background_photons_per_s: Input should be less than or equal to"),
    Case("lidar dark counts 1e20", lidar("options.detector.expert_dark_count_rate_hz", 1e20), "study.options.detector.expert_dark_count_rate_hz: Input should be less than or equal to"),
    Case("lidar oracle label named as a planner", with_("study.planners", ["bound"], lidar("planner_opts", {"bound": {"strategy": "oracle_hessian"}})), "study.planners[0]: the label 'bound' of 'oracle_hessian' (reads the true depth: a bound, not a planner) must start with 'oracle'"),
    Case("lidar oracle of a reconstruction the study lacks", with_("study.planners", ["oracle_greedy"], lidar("planner_opts", {"oracle_greedy": {"oracle": {"reconstruction": "shading"}}})), "study.planner_opts.oracle_greedy.oracle.reconstruction: 'shading' is not one of study.reconstructions"),
    Case("lidar sequential on a flash", with_("study.planners", ["sequential"], with_("study.options.flash.receiver_px", [64, 48], lidar("sensor", "flash"))), "study.planners[0]: 'sequential' asks the LIDAR back between rounds, but a flash LIDAR measures its receiver pixels"),
    Case("micromirror dots short of render samples", with_("study", {**LIDAR, "sensor": "micromirror_flash", "options": {"transient": {"spp": 8}, "micromirror": {"receiver_px": [4, 4]}}}, with_("render.camera", {**PERSPECTIVE, "height": 64})), "study.options: transient.spp 8 gives each lit guide pixel 0.031 render samples (a 4 x 4 receiver pixel covers 256 of the 64 x 64 guide pixels); at least 4 are needed (about 16 for a clean return): spp >= 1024, or a larger receiver_px"),
    Case("lidar gate prior wider than the window", lidar("options.gate", {"max_slope_deg": 20}), "study.options.steered_beam.window_m: 8 m cannot hold the gate prior: it needs more than"),
    Case("lidar budget fit without a budget", lidar("planner_opts", {"random": {"fit": {"kind": "budget"}}}), "a budget fit needs budget_s, budget_j or both"),
    Case("lidar energy budget on expert photon scales", with_("study.options.detector", {"expert_signal_photons": 100}, lidar("planner_opts", {"random": {"fit": {"kind": "budget", "budget_j": 0.1}}})), "study.planner_opts.random.fit.budget_j: an energy budget needs the instrument's pulse energy"),
    Case("lidar receiver fit on a steered beam", lidar("planner_opts", {"random": {"fit": {"kind": "receiver"}}}), "study.planner_opts.random.fit: a receiver fit is for the micromirror_flash sensor"),
    Case("lidar scan-time fit without its reference", lidar("planner_opts", {"random": {"fit": {"kind": "scan_time"}}}), "study.planner_opts.random.fit.reference: 'grid' must be an unfitted planner of study.planners (random)"),
    Case("lidar zero slew rate", lidar("options.steered_beam.max_rate_rad_s", 1e-300), "study.options.steered_beam.max_rate_rad_s: Input should be greater than or equal to 0.000001"),
    Case("lidar zero acceleration", lidar("options.steered_beam.max_accel_rad_s2", 1e-300), "study.options.steered_beam.max_accel_rad_s2: Input should be greater than or equal to"),
    Case("lidar pulse rate 1e-300", lidar("options.steered_beam.pulse_rate_hz", 1e-300), "study.options.steered_beam.pulse_rate_hz: Input should be greater than or equal to 0.001"),
    Case("lidar settle 1e300 ms", lidar("options.steered_beam.settle_ms", 1e300), "study.options.steered_beam.settle_ms: Input should be less than or equal to"),
    Case("lidar footprint rays 1e6", lidar("options.steered_beam.footprint_rays", 1_000_000), "study.options.steered_beam.footprint_rays: Input should be less than or equal to 4096"),
    Case("lidar transient spp 1e7", lidar("options.transient.spp", 10_000_000), "study.options.transient.spp: Input should be less than or equal to 65536"),
    Case("lidar pulses per point 1e9", lidar("options.steered_beam.pulses_per_point", 10**9), "study.options.steered_beam.pulses_per_point: Input should be less than or equal to 1000000"),
    Case("lidar detector pulses 1e9", lidar("options.detector.pulses", 10**9), "study.options.detector.pulses: Input should be less than or equal to 1000000"),
    Case("lidar fwhm 1 s", lidar("options.pulse.fwhm_ns", 1e9), "study.options.pulse.fwhm_ns: Input should be less than or equal to 10000"),
    Case("lidar jitter 1 s", lidar("options.pulse.jitter_ns", 1e9), "study.options.pulse.jitter_ns: Input should be less than or equal to 10000"),
    Case("lidar bins of a micrometre", lidar("options.bin_range_m", 1e-6), "study.options.bin_range_m: 1e-06 m makes 8e+06 time bins of the 8 m window (at most 100000)"),
    Case("lidar pulse wider than the bins allow", lidar("options", {"bin_range_m": 1e-3, "margin_m": 0.001, "steered_beam": {"window_m": 0.01}, "pulse": {"fwhm_ns": 9000}}), "study.options.pulse.fwhm_ns: a 9000 ns pulse spans 1.35e+06 time bins of 0.001 m (at most 100000)"),
    Case("lidar batch 1e9 beams", lidar("options.steered_beam.batch", 10**9), "study.options.steered_beam.batch: Input should be less than or equal to 1000000"),
    Case("lidar flash receiver 1e5 px", lidar("options", {"flash": {"receiver_px": [100000, 64]}}), "Input should be less than or equal to 8192", ),
    Case("lidar micromirror receiver 0 px", lidar("options", {"micromirror": {"receiver_px": [64, 0]}}), "Input should be greater than or equal to 1"),
    Case("lidar flash pulse rate 0", with_("study.sensor", "flash", lidar("options.flash.pulse_rate_hz", 0)), "study.options.flash.pulse_rate_hz: Input should be greater than or equal to 0.001"),
    Case("sweep product above the unit limit", {**GOOD, "sweep": {"render.spp": list(range(1, 101)), "study.trials": list(range(1, 101))}}, "sweep: 100 x 100 sweep points x 1 terrain seeds = units = 1e+04, more than the limit of 5e+03 (set SIMLUNAR_MAX_UNITS", env={"SIMLUNAR_MAX_UNITS": "5000"}),
    Case("sweep product of a million", {**GOOD, "sweep": {"render.spp": list(range(1, 101)), "study.trials": list(range(1, 101)), "seed": list(range(100))}}, "sweep: 100 x 100 x 100 sweep points x 1 terrain seeds = units = 1e+06, more than the limit of 1e+04"),
    Case("SIMLUNAR_MAX_UNITS not a number", GOOD, "SIMLUNAR_MAX_UNITS=lots: expected a positive count", env={"SIMLUNAR_MAX_UNITS": "lots"}),
]  # fmt: skip


@pytest.mark.parametrize("case", LIDAR_CASES, ids=[c.name for c in LIDAR_CASES])
def test_lidar_and_size_case_exits_2_with_one_line(case, tmp_path, monkeypatch):
    _run_case(case, tmp_path, monkeypatch)


def test_the_good_lidar_config_passes_the_checks(tmp_path):
    from simlunar.config.loading import validate_data
    from simlunar.pipeline.preflight import check_units
    from simlunar.pipeline.runner import expand

    flash = with_("study.options", {"flash": {"receiver_px": [64, 48]}}, LIDAR_GOOD)
    for data in (LIDAR_GOOD, with_("study.sensor", "flash", flash)):
        check_units(expand(validate_data(data, base_dir=tmp_path)))


# structured-light rigs that cannot work, refused before config.yaml is written
SCAN_GOOD = with_("study", SCANNER)
NO_GPU = pytest.mark.skipif(Path("/dev/nvidia0").exists(), reason="a GPU is present")


def scan(key: str, value, base=None) -> dict:
    return with_(f"study.{key}", value, base or SCAN_GOOD)


def lock_folder(d: Path) -> None:
    (d / "results").mkdir()
    (d / "results" / ".lock").mkdir()


SCAN_CASES = [
    Case("rig projector inside the bed (aerial)", scan("options.rig.altitude_m", 0.01, scan("rig", "aerial")), "study.options.rig: the projector is 0.01 m above the terrain's median height, inside its relief (at least 10 cells = 2 m"),
    Case("rig projector inside the bed (moonyard)", scan("options.rig.distance_m", 0.001, with_("terrain.preset", "moonyard", SCAN_GOOD)), "the projector is 0.00094 m above the terrain's median height, inside its relief"),
    Case("rig fill 1e-6", scan("options.rig.fill", 1e-6), "study.options.rig.fill: Input should be greater than or equal to 0.01"),
    Case("rig fill 0.01 puts the projector in the bed", scan("options.rig.fill", 0.01), "study.options.rig: the projector is 0.336 m above the terrain's median height"),
    Case("rig projector fov 179 deg", scan("options.rig.fov_x_deg", 179), "study.options.rig.fov_x_deg: Input should be less than or equal to 120"),
    Case("rig camera fov 179 deg", scan("options.rig.cam_fov_x_deg", 179), "study.options.rig.cam_fov_x_deg: Input should be less than or equal to 120"),
    Case("rig baseline 1000 km", scan("options.rig.baseline_m", 1e6), "study.options.rig: a baseline of 1e+06 m is more than 5 x the projector's 32.2 m standoff"),
    Case("gray black threshold 1.0", scan("options.gray_opts.black_threshold", 1.0), "study.options.gray_opts.black_threshold: Input should be less than 0.8"),
    Case("gray white threshold 0.9", scan("options.gray_opts.white_threshold", 0.9), "study.options.gray_opts.white_threshold: Input should be less than 0.8"),
    Case("sun 1e30 x the projector", scan("scan_light", "sun", with_("render.light", {"kind": "sun", "elevation_deg": 40, "irradiance": 1e30}, SCAN_GOOD)), "render.light.irradiance: Input should be less than or equal to 1000000"),
    Case("projector blur 1000 px", scan("projector_blur_px", 1000), "study.projector_blur_px: 1000 px blurs the pattern over the whole 256 x 192 image (at most 48 px"),
    Case("projector blur '1000 px'", scan("projector_blur_px", "1000 px"), "study.projector_blur_px: 1000 px blurs the pattern"),
    Case("camera blur 500 px", scan("camera_blur_px", 500), "study.camera_blur_px: 500 px blurs the pattern over the whole 256 x 192 image"),
    Case("camera blur '1 m'", scan("camera_blur_px", "1 m"), "study.camera_blur_px:"),
    Case("camera blur negative", scan("camera_blur_px", -1), "study.camera_blur_px: Input should be greater than or equal to 0"),
    Case("projector gamma 1e9", scan("projector_gamma", 1e9), "study.projector_gamma: Input should be less than or equal to 10"),
    Case("SIMLUNAR_VARIANT unknown", GOOD, "SIMLUNAR_VARIANT=rgb_fast: unknown variant", env={"SIMLUNAR_VARIANT": "rgb_fast"}),
    Case("lock file is a folder", GOOD, "results/.lock is not a file", setup=lock_folder),
    Case("terrain spacing 1e-300", dem_cfg(spacing_m=1e-300), "dem.npy: a spacing of 1e-300 m per cell is below 1e-06 m", setup=files(dem__npy=good_dem)),
]  # fmt: skip


@pytest.mark.parametrize("case", SCAN_CASES, ids=[c.name for c in SCAN_CASES])
def test_rig_and_environment_case_exits_2_with_one_line(case, tmp_path, monkeypatch):
    _run_case(case, tmp_path, monkeypatch)


def test_camera_blur_with_its_unit_is_accepted_as_documented(tmp_path):
    from simlunar.config.loading import validate_data

    cfg = validate_data(scan("camera_blur_px", "1 px", scan("projector_blur_px", "0.5 px")))
    assert (cfg.study.camera_blur_px, cfg.study.projector_blur_px) == (1.0, 0.5)


SCAN_CMDS = [
    Cmd("run CUDA without a GPU exits 3", ("run", "exp.yaml", "--out", "o"), "SIMLUNAR_VARIANT=cuda_ad_rgb: cuda_ad_rgb requested but unusable", code=3, setup=yaml_file("exp.yaml", GOOD), env={"SIMLUNAR_VARIANT": "cuda_ad_rgb"}, marks=[NO_GPU]),
    Cmd("render CUDA without a GPU exits 3", ("render", "scene.yaml", "--out", "r"), "cuda_ad_rgb requested but unusable", code=3, setup=yaml_file("scene.yaml", SCENE), env={"SIMLUNAR_VARIANT": "cuda_ad_rgb"}, marks=[NO_GPU]),
    Cmd("terrain preset grid 2e7 x 2e7", ("terrain", "big.yaml", "--out", "t"), "big.yaml: grid: 20000000 x 20000000 cells = 4e+14, more than the limit", setup=yaml_file("big.yaml", {"grid": {"rows": 20000000, "cols": 20000000}})),
    Cmd("terrain preset grid above a lowered limit", ("terrain", "big.yaml", "--out", "t"), "more than the limit of 1e+03", setup=yaml_file("big.yaml", {"grid": {"rows": 64, "cols": 64}}), env={"SIMLUNAR_MAX_CELLS": "1000"}),
    Cmd("terrain --stats sidecar spacing 1e-300", ("terrain", "dem.npy", "--stats"), "--stats: dem.npy: a spacing of 1e-300 m per cell is below 1e-06 m", setup=side_json("1e-300")),
    Cmd("terrain --stats sidecar spacing 1e-9", ("terrain", "dem.npy", "--stats"), "a spacing of 1e-09 m per cell is below", setup=side_json("1e-9")),
]  # fmt: skip


@pytest.mark.parametrize(
    "case", [pytest.param(c, marks=c.marks) for c in SCAN_CMDS], ids=[c.name for c in SCAN_CMDS]
)
def test_rig_and_environment_command_keeps_the_promise(case, tmp_path, monkeypatch, capsys):
    test_every_subcommand_keeps_the_promise(case, tmp_path, monkeypatch, capsys)


def test_there_are_at_least_60_fault_cases():
    fault = FAULT_CASES + FAULT_CMDS + LIDAR_CASES + SCAN_CASES + SCAN_CMDS + OTHER_CASES
    assert len(fault) >= 60
    assert len({c.name for c in fault}) == len(fault)


# bounded YAML, resumable tables, an empty interior region
SMALL_VIEW = {**PERSPECTIVE, "width": 20, "height": 16}
OTHER_CASES = [
    Case("yaml 5000 nested brackets", "name: x\nterrain: " + "[" * 5000 + "]" * 5000 + "\n", "exp.yaml: line 2: collections nested more than 100 deep"),
    Case("yaml 5000 nested flow mappings", "name: x\nterrain: " + "{a: " * 5000 + "1" + "}" * 5000 + "\n", "collections nested more than 100 deep"),
    Case("yaml 3000 nested block mappings", "name: x\nterrain:\n" + "".join("  " * i + f"k{i}:\n" for i in range(1, 3000)) + "  " * 3000 + "v: 1\n", "exp.yaml: line 102: collections nested more than 100 deep"),
    Case("yaml 11 MB document", "name: x\n#" + "a" * 11_000_000 + "\n", "exp.yaml: the document has 1.1e+07 characters, more than 1e+07"),
    Case("interior region empty", with_("study.score_region", "interior", with_("study.densities", ["1/64"], with_("render.camera", SMALL_VIEW))), "study.score_region: interior: a border band of 8.0 px leaves no interior cell in a 16 x 20 grid"),
    Case("interior region empty (both)", with_("study.score_region", "both", with_("study.densities", ["1/64"], with_("render.camera", SMALL_VIEW))), "study.score_region: both: a border band of 8.0 px leaves no interior cell"),
]  # fmt: skip


@pytest.mark.parametrize("case", OTHER_CASES, ids=[c.name for c in OTHER_CASES])
def test_bounded_input_case_exits_2_with_one_line(case, tmp_path, monkeypatch):
    _run_case(case, tmp_path, monkeypatch)
