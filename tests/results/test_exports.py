"""Scan export: a small real gray-code scan written out and read back with OpenCV.

One module-scoped scan (64 x 48 projector, 96 x 72 camera, 12-bit sensor with shot and read
noise, 4 spp) on a bumpy patch with an albedo pattern; the checks decode the exported PNGs
with OpenCV's own decoder and reproject the exported cloud with OpenCV's own projection.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.imaging.exr import read_exr
from simlunar.imaging.sensor import SensorModel
from simlunar.render.capture import CaptureOptions, RenderCapture
from simlunar.results import exports
from simlunar.scanner import rigs
from simlunar.scanner.codings import make_coding
from simlunar.scanner.gray_code import GrayCodeOptions, gray_code_scan
from simlunar.terrain.types import Terrain

pytestmark = pytest.mark.render

N, SPACING, ORIGIN = 100, 0.02, (-1.0, 1.0)  # a 2 m x 2 m bench-top patch
PROJ, CAM = (64, 48), (96, 72)
ROOT = Path(__file__).resolve().parents[2]
QUICKSTART = str(ROOT / "experiments" / "quickstart.yaml")


def _capture():
    x = ORIGIN[0] + SPACING * (np.arange(N) + 0.5)
    xx, yy = np.meshgrid(x, ORIGIN[1] - SPACING * (np.arange(N) + 0.5))
    heights = 0.1 * np.exp(-(xx**2 + yy**2) / 0.1) + 0.05 * np.sin(3 * xx)
    albedo = (0.3 + 0.2 * (np.sin(7 * xx) * np.sin(5 * yy) > 0)).astype(np.float32)
    terr = Terrain(heights, albedo, SPACING, ORIGIN)
    rig = rigs.moonyard_rig(proj_size=PROJ, cam_size=CAM)
    sensor = SensorModel(full_well_e=20000.0, read_noise_e=5.0, bits=12)
    cap = RenderCapture(
        terr, rig, CaptureOptions(spp=4, seed=1, camera_blur=0.7), sensor=sensor, rng=3
    )
    return rig, cap


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    rig, cap = _capture()
    gray = gray_code_scan(cap, rig, GrayCodeOptions(keep_frames=True))
    folder = tmp_path_factory.mktemp("export") / "unit0"
    exports.write_scan_export(folder, exports.scan_export_payload(gray, rig))
    return rig, gray, folder


def _frames(folder, sub):
    paths = sorted((folder / sub).glob("*.png"))
    return paths, [cv2.imread(str(p), cv2.IMREAD_UNCHANGED) for p in paths]


def test_layout_and_frame_order_names(scan):
    _, gray, folder = scan
    paths, f8 = _frames(folder, "frames8")
    _, f16 = _frames(folder, "frames16")
    # 6 column + 6 row bits, pattern and inverse each, then white and black
    assert [p.name for p in paths[:3]] == ["00_col0.png", "01_col0_inv.png", "02_col1.png"]
    assert [p.name for p in paths[-3:]] == ["23_row5_inv.png", "24_white.png", "25_black.png"]
    assert {f.dtype for f in f8} == {np.dtype(np.uint8)}
    assert {f.dtype for f in f16} == {np.dtype(np.uint16)}
    assert f8[0].shape == (CAM[1], CAM[0])
    # the exported frames are the sensor frames the decoder used, quantised
    used = np.concatenate(
        [gray.frames["images"], gray.frames["white"][None], gray.frames["black"][None]]
    ).astype(np.float64)  # float32 frames; the export quantises in float64
    assert np.array_equal(np.stack(f8), np.rint(np.clip(used, 0, 1) * 255).astype(np.uint8))
    assert np.array_equal(np.stack(f16), np.rint(np.clip(used, 0, 1) * 65535).astype(np.uint16))
    # sensor frames, not ideal patterns: the black frame has read noise, the white frame is
    # not a constant 255
    assert np.stack(f16)[-1].std() > 0 and len(np.unique(f8[-2])) > 20
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["opencv_black_threshold_8bit"] == 13  # 0.05 * 255 = 12.75
    assert manifest["opencv_white_threshold_8bit"] == 3  # 0.01 * 255 = 2.55
    assert manifest["frames"] == [p.name for p in paths]


def test_opencv_getprojpixel_on_the_exported_8bit_stack_agrees_with_simlunar(scan):
    _, gray, folder = scan
    _, f8 = _frames(folder, "frames8")
    pattern, white, black = f8[:-2], f8[-2], f8[-1]
    g = cv2.structured_light.GrayCodePattern.create(*PROJ)
    assert g.getNumberOfPatternImages() == len(pattern)
    g.setBlackThreshold(13)
    g.setWhiteThreshold(3)
    # OpenCV's shadow mask (decode()): white - black > blackThreshold
    lit = white.astype(int) - black.astype(int) > 13
    cv_col = np.full(lit.shape, -1)
    cv_row = np.full(lit.shape, -1)
    for y, x in zip(*np.nonzero(lit)):
        err, (px, py) = g.getProjPixel(pattern, int(x), int(y))
        if not err:
            cv_col[y, x], cv_row[y, x] = px, py
    dec = gray.decode
    both = dec.valid & (cv_col >= 0)
    assert both.mean() > 0.5  # most of the camera sees a decoded projector pixel
    agree = (cv_col[both] == dec.col[both]) & (cv_row[both] == dec.row[both])
    assert agree.mean() >= 0.995, f"{agree.mean():.4f}"
    # the exported maps are simlunar's decode (integer pixels, -1 where invalid)
    maps = read_exr(folder / "decode.exr")
    assert np.array_equal(maps["valid"] > 0, dec.valid)
    assert np.array_equal(maps["col"][dec.valid], dec.col[dec.valid])
    assert np.array_equal(maps["row"][dec.valid], dec.row[dec.valid])
    assert np.all(maps["col"][~dec.valid] == -1)
    # u, v: simlunar's projector coordinates shifted to OpenCV's convention (centre at col)
    assert np.allclose(maps["u"][dec.valid], dec.col[dec.valid])


def test_16bit_frames_are_the_8bit_frames_at_finer_steps(scan):
    _, _, folder = scan
    _, f8 = _frames(folder, "frames8")
    _, f16 = _frames(folder, "frames16")
    # 65535 = 257 * 255: one 8-bit step is 257 16-bit steps
    assert np.abs(np.stack(f16).astype(int) - 257 * np.stack(f8).astype(int)).max() <= 128


def test_exported_calibration_reprojects_the_cloud_with_cv2_projectpoints(scan):
    rig, gray, folder = scan
    fs = cv2.FileStorage(str(folder / "calibration.yml"), cv2.FILE_STORAGE_READ)
    assert fs.isOpened()
    K = fs.getNode("camera_matrix").mat()
    dist = fs.getNode("camera_distortion").mat()
    Kp = fs.getNode("projector_matrix").mat()
    distp = fs.getNode("projector_distortion").mat()
    Rc, tc = fs.getNode("camera_R_world").mat(), fs.getNode("camera_t_world").mat()
    R, T = fs.getNode("R").mat(), fs.getNode("T").mat()
    size = fs.getNode("camera_image_size")
    assert [int(size.at(i).real()) for i in range(2)] == list(CAM)
    assert fs.getNode("baseline_m").real() == pytest.approx(rig.baseline, rel=1e-15)
    assert np.linalg.norm(T) == pytest.approx(rig.baseline, rel=1e-12)
    fs.release()

    cloud = exports.read_cloud_ply(folder / "cloud.ply")
    pts = np.stack([cloud["x"], cloud["y"], cloud["z"]], axis=-1)
    # the exported cloud is the scan's cloud, point for point
    assert np.array_equal(pts, gray.cloud.points)
    assert len(pts) > 0.5 * CAM[0] * CAM[1]
    # each point came from camera pixel (cam_col, cam_row) (ray-plane triangulation: on its ray)
    uv, _ = cv2.projectPoints(pts, cv2.Rodrigues(Rc)[0], tc, K, dist)
    cam = np.stack([cloud["cam_col"], cloud["cam_row"]], axis=-1)
    assert np.abs(uv[:, 0] - cam).max() < 0.01
    # and on its decoded projector column plane; R, T chain camera -> projector
    x_cam = pts @ Rc.T + tc.ravel()
    uvp, _ = cv2.projectPoints(x_cam, cv2.Rodrigues(R)[0], T, Kp, distp)
    assert np.abs(uvp[:, 0, 0] - cloud["proj_u"]).max() < 0.01
    assert np.array_equal(cloud["proj_u"], gray.cloud.proj_uv[:, 0] - 0.5)


def test_a_wrong_calibration_would_fail_the_reprojection_check(scan):
    # the 0.01 px check has teeth: a half-pixel principal point (simlunar's convention
    # instead of OpenCV's) moves every point by 0.5 px
    rig, _, folder = scan
    cloud = exports.read_cloud_ply(folder / "cloud.ply")
    pts = np.stack([cloud["x"], cloud["y"], cloud["z"]], axis=-1)
    Rc, tc = rig.camera.pose.extrinsics_opencv()
    uv, _ = cv2.projectPoints(pts, cv2.Rodrigues(Rc)[0], tc, rig.camera.intrinsics.K, None)
    cam = np.stack([cloud["cam_col"], cloud["cam_row"]], axis=-1)
    assert np.abs(uv[:, 0] - cam).min() > 0.49


@pytest.fixture(scope="module")
def phase_scan(tmp_path_factory):
    """The same patch scanned by 3-step phase shifting (OpenCV's PSP takes 3 frames)."""
    rig, cap = _capture()
    coding = make_coding("phase_shift", {"steps": 3, "period_px": 8.0, "ratio": 8.0})
    ps_scan = coding.scan(cap, rig, keep_frames=True)
    folder = tmp_path_factory.mktemp("export_ps") / "unit0"
    exports.write_scan_export(folder, exports.scan_export_payload(ps_scan, rig))
    return rig, ps_scan, folder


def test_phase_shift_export_layout_and_manifest(phase_scan):
    _, ps_scan, folder = phase_scan
    paths, f8 = _frames(folder, "frames8")
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["coding"] == "phase_shift" and manifest["steps"] == 3
    # columns: periods 512, 64, 8 px (64 px wide); rows: 64, 8 (48 px high); 3 shifts each
    assert manifest["periods_px"] == {"col": [512.0, 64.0, 8.0], "row": [64.0, 8.0]}
    assert [p.name for p in paths[:4]] == ["00_col0_s0.png", "01_col0_s1.png", "02_col0_s2.png",
                                           "03_col1_s0.png"]  # fmt: skip
    assert [p.name for p in paths[-2:]] == ["15_white.png", "16_black.png"]
    assert manifest["frames"] == [p.name for p in paths] and len(f8) == 5 * 3 + 2
    used = np.concatenate(
        [ps_scan.frames["images"], ps_scan.frames["white"][None], ps_scan.frames["black"][None]]
    ).astype(np.float64)
    assert np.array_equal(np.stack(f8), np.rint(np.clip(used, 0, 1) * 255).astype(np.uint8))
    maps = read_exr(folder / "decode.exr")
    dec = ps_scan.decode
    assert np.array_equal(maps["valid"] > 0, dec.valid) and dec.valid.mean() > 0.5
    assert np.allclose(maps["u"][dec.valid], dec.u[dec.valid] - 0.5, atol=1e-4)  # float32


def test_opencv_sinusoidal_pattern_computes_the_exported_wrapped_phase(phase_scan):
    # OpenCV's PSP (3 frames shifted by 2 pi / 3) on the exported 8-bit frames of the finest
    # column level gives the wrapped phase that simlunar's decoded u names: 2 pi (u + offset)
    # / period, u in simlunar's convention (exported u + 0.5). OpenCV smooths its phase map
    # spatially, so the comparison keeps valid pixels away from the lit region's edges and
    # from the phase's wrap (where a smoothed wrapped phase is meaningless).
    from scipy import ndimage

    folder = phase_scan[2]
    paths, f8 = _frames(folder, "frames8")
    manifest = json.loads((folder / "manifest.json").read_text())
    period = manifest["periods_px"]["col"][-1]
    offset = manifest["phase_offsets_px"]["col"]
    finest = [f8[i] for i, p in enumerate(paths) if p.stem.split("_", 1)[1].startswith("col2_")]
    assert len(finest) == 3
    params = cv2.structured_light.SinusoidalPattern.Params()
    params.width, params.height = CAM
    params.nbrOfPeriods = round(PROJ[0] / period)
    params.methodId = cv2.structured_light.PSP
    params.setMarkers = False
    sp = cv2.structured_light.SinusoidalPattern.create(params)
    cv_phase, _ = sp.computePhaseMap(finest)
    maps = read_exr(folder / "decode.exr")
    ours = np.mod(2 * np.pi * (maps["u"].astype(np.float64) + 0.5 + offset) / period, 2 * np.pi)
    valid = ndimage.binary_erosion(maps["valid"] > 0, iterations=3)
    away = (ours > 0.6) & (ours < 2 * np.pi - 0.6)
    keep = valid & away
    assert keep.sum() > 0.3 * CAM[0] * CAM[1]
    diff = np.abs(np.angle(np.exp(1j * (cv_phase[keep] - ours[keep]))))
    # tolerance: 8-bit frames, sensor noise and OpenCV's smoothing; measured on the CPU
    # (llvm) variant: median 0.048 rad, 95th percentile 0.14, max 0.26 (0.1 rad is 1/60 of a
    # fringe, 0.13 projector px at the 8 px period)
    med, p95 = np.median(diff), np.percentile(diff, 95)
    assert med < 0.1 and p95 < 0.3, (med, p95)
    # the exported phase maps: the finest level's wrapped phase is OpenCV's, and the absolute
    # phase wraps to it
    phase = read_exr(folder / "phase.exr")
    wrapped = phase["col2_wrapped"].astype(np.float64)
    d_wrapped = np.abs(np.angle(np.exp(1j * (cv_phase[keep] - wrapped[keep]))))
    assert np.median(d_wrapped) < 0.1 and np.percentile(d_wrapped, 95) < 0.3
    absolute = phase["col_absolute"].astype(np.float64)
    np.testing.assert_allclose(np.mod(absolute[keep], 2 * np.pi), ours[keep], atol=1e-4)
    d_abs = np.abs(np.angle(np.exp(1j * (absolute[keep] - wrapped[keep]))))
    assert np.median(d_abs) < 0.05
    # the check has teeth: simlunar's half-pixel convention forgotten (u without + 0.5) is
    # 2 pi 0.5 / 8 = 0.39 rad off
    wrong = np.mod(2 * np.pi * (maps["u"].astype(np.float64) + offset) / period, 2 * np.pi)
    assert np.median(np.abs(np.angle(np.exp(1j * (cv_phase[keep] - wrong[keep]))))) > 0.2


def test_calibration_yaml_keeps_full_precision(tmp_path):
    calib = {"M": np.array([[1 / 3, -2e-17], [np.pi, 1e300]]), "size": [640, 480], "b": 0.1}
    exports.write_calibration_yaml(tmp_path / "c.yml", calib)
    assert (tmp_path / "c.yml").read_text().startswith("%YAML:1.0\n")
    fs = cv2.FileStorage(str(tmp_path / "c.yml"), cv2.FILE_STORAGE_READ)
    assert np.array_equal(fs.getNode("M").mat(), calib["M"])
    assert fs.getNode("b").real() == 0.1
    with pytest.raises(ValueError, match="not finite"):
        exports.write_calibration_yaml(tmp_path / "d.yml", {"M": np.full((1, 1), np.nan)})


def test_quantize_rounds_and_clips():
    x = np.array([-0.1, 0.0, 0.5 / 255, 0.49 / 255, 1.0, 1.7])
    assert exports.quantize(x, 8).tolist() == [0, 0, 0, 0, 255, 255]  # 0.5 ties to even
    assert exports.quantize(np.array([1.5 / 255]), 8).tolist() == [2]
    assert exports.quantize(np.array([1 / 65535, 0.5]), 16).tolist() == [1, 32768]
    with pytest.raises(ValueError):
        exports.quantize(x, 12)


def test_run_with_save_scans_writes_one_folder_per_unit(tmp_path):
    out = tmp_path / "scan"
    args = [
        "run",
        str(ROOT / "experiments" / "scanner_ambiguity.yaml"),
        "--out",
        str(out),
        "--save-scans",
        "--no-progress",
        "--no-figures",
        *("--set", "terrain.scale=0.125"),
        *("--set", "study.projector_px=[32, 24]"),
        *("--set", "study.camera_px=[48, 36]"),
        *("--set", "render.spp=1"),
        *("--set", "study.modes=[gray_code, phase_shift]"),
        *("--set", "study.metrics=[mse]"),
        *("--set", "sweep={}"),
    ]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    unit = out / "scans" / "unit0"
    # one folder per coding the study scanned, named in the unit's manifest
    manifest = json.loads((unit / "manifest.json").read_text())
    assert manifest["codings"] == ["gray_code", "phase_shift"] and manifest["kind"] == "codings"
    gray, phase = unit / "gray_code", unit / "phase_shift"
    assert len(list((gray / "frames8").glob("*.png"))) == 2 * (5 + 5) + 2
    for folder in (gray, phase):
        assert {"decode.exr", "cloud.ply", "calibration.yml", "manifest.json"} <= {
            p.name for p in folder.iterdir()
        }
    assert not (gray / "phase.exr").exists()
    # phase shift: the wrapped phase of every level and the absolute phase per axis
    maps = read_exr(phase / "phase.exr")
    levels = json.loads((phase / "manifest.json").read_text())["periods_px"]
    assert set(maps) == {f"col{i}_wrapped" for i in range(len(levels["col"]))} | {
        f"row{i}_wrapped" for i in range(len(levels["row"]))
    } | {"col_absolute", "row_absolute"}
    assert "save_scans: true" in (out / "config.yaml").read_text()


def test_save_scans_on_a_sampling_study_is_a_user_error(tmp_path):
    out = tmp_path / "q"
    r = CliRunner().invoke(app, ["run", QUICKSTART, "--out", str(out), "--save-scans"])
    assert r.exit_code == 2
    assert "--save-scans" in r.output and "scanner" in r.output
    assert not out.exists()


def test_save_scans_without_a_gray_code_scan_is_a_user_error(tmp_path):
    out = tmp_path / "d"
    args = ["run", str(ROOT / "experiments" / "scanner_ambiguity.yaml"), "--out", str(out)]
    args += ["--set", "study.save_scans=true", "--set", "study.modes=[data_reduction]"]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 2
    assert "save_scans" in r.output and "gray_code" in r.output
    assert not out.exists()
    r = CliRunner().invoke(
        app, [*args[:4], "--set", "study.modes=[data_reduction]", "--save-scans"]
    )
    assert r.exit_code == 2 and "--save-scans" in r.output
    assert not out.exists()


def test_save_scans_checks_every_sweep_point(tmp_path):
    # --save-scans is applied before validation: a sweep point without a gray-code scan is
    # refused in one line (it used to reach runner.expand and crash with a traceback)
    out = tmp_path / "s"
    args = ["run", str(ROOT / "experiments" / "scanner_ambiguity.yaml"), "--out", str(out)]
    args += ["--set", "study.modes=[gray_code]"]
    args += ["--set", "sweep={study.modes: [[gray_code], [data_reduction]]}", "--save-scans"]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert "sweep.study.modes[1]" in lines[0] and "gray_code" in lines[0]
    assert not out.exists()


def test_scan_folders_follow_their_units(tmp_path, monkeypatch):
    """manifest.json names the unit's key; folders of units no longer produced are removed
    with the units, and a cached unit whose export is missing is computed again."""
    import shutil

    from simlunar.pipeline import runner
    from simlunar.results.exports import export_unit_key

    out = tmp_path / "scan"
    args = [
        "run",
        str(ROOT / "experiments" / "scanner_ambiguity.yaml"),
        "--out",
        str(out),
        "--no-progress",
        "--no-figures",
        "--save-scans",
        *("--set", "terrain.scale=0.125"),
        *("--set", "study.projector_px=[16, 12]"),
        *("--set", "study.camera_px=[24, 18]"),
        *("--set", "render.spp=1"),
        *("--set", "study.modes=[gray_code]"),
        *("--set", "study.metrics=[mse]"),
        *("--set", "sweep={seed: [1, 2]}"),
    ]

    def run():
        r = CliRunner().invoke(app, args)
        assert r.exit_code == 0, r.output
        keys = json.loads((out / "provenance.json").read_text())["unit_keys"]
        return r.output, keys

    def exported():
        return {p.name: export_unit_key(p) for p in (out / "scans").iterdir()}

    _, keys = run()
    assert exported() == {"unit0": keys[0], "unit1": keys[1]}
    # a leftover folder and the export of another state of unit1: removed / made again
    shutil.copytree(out / "scans" / "unit0", out / "scans" / "unit7")
    manifest = out / "scans" / "unit1" / "manifest.json"
    manifest.write_text(json.dumps({**json.loads(manifest.read_text()), "unit_key": "0" * 16}))
    text, _ = run()
    assert "(1 cached, 1 computed)" in text
    assert exported() == {"unit0": keys[0], "unit1": keys[1]}
    # a missing export of a cached unit is written again (the unit is computed again)
    shutil.rmtree(out / "scans" / "unit0")
    text, _ = run()
    assert "(1 cached, 1 computed)" in text and exported()["unit0"] == keys[0]
    text, _ = run()
    assert "(2 cached, 0 computed)" in text
    # new unit keys (another simlunar): the old units and their exports are replaced
    monkeypatch.setattr(runner, "CACHE_VERSION", runner.CACHE_VERSION + 1000)
    text, new_keys = run()
    assert "(0 cached, 2 computed)" in text and set(new_keys).isdisjoint(keys)
    assert exported() == {"unit0": new_keys[0], "unit1": new_keys[1]}


def test_a_partly_deleted_export_is_restored_and_a_full_disk_is_exit_3(tmp_path, monkeypatch):
    """Deleting a frame and the decoded maps of a finished export makes the next run write
    it again, byte for byte; a disk full while OpenEXR writes (its RuntimeError wraps the
    OS error) is one line and exit 3, with the units kept."""
    import hashlib

    import OpenEXR

    out = tmp_path / "scan"
    args = [
        "run",
        str(ROOT / "experiments" / "scanner_ambiguity.yaml"),
        "--out",
        str(out),
        "--no-progress",
        "--no-figures",
        "--save-scans",
        *("--set", "terrain.scale=0.125"),
        *("--set", "study.projector_px=[16, 12]"),
        *("--set", "study.camera_px=[24, 18]"),
        *("--set", "render.spp=1"),
        *("--set", "study.modes=[gray_code]"),
        *("--set", "study.metrics=[mse]"),
        *("--set", "sweep={}"),
    ]
    unit = out / "scans" / "unit0"

    def export_tree():
        return {
            str(p.relative_to(unit)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(unit.rglob("*"))
            if p.is_file()
        }

    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    first = export_tree()
    (unit / "gray_code" / "decode.exr").unlink()
    sorted((unit / "gray_code" / "frames16").glob("*.png"))[3].unlink()

    def full_disk(self, path):
        raise RuntimeError(
            f'Failed to write pixel data to image file "{path}". No space left on device.'
        )

    with monkeypatch.context() as m:
        m.setattr(OpenEXR.File, "write", full_disk)
        r = CliRunner().invoke(app, args)
    assert r.exit_code == 3, r.output
    assert r.stderr.splitlines() == [
        f"error: {unit / 'gray_code' / 'decode.exr'}: No space left on device"
    ]
    assert len(list((out / "units").glob("*.json"))) == 1
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    assert "(0 cached, 1 computed)" in r.output
    assert export_tree() == first
