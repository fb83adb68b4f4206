"""Rendered acceptance tests of the scanner (small Mitsuba renders, a few seconds in all)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import ndimage

from simlunar.geometry import Camera, Intrinsics, Pose, Projector, Rig
from simlunar.render.capture import (
    EXPOSURE_PERCENTILE,
    CaptureOptions,
    RenderCapture,
    camera_truth,
    render_guide,
)
from simlunar.scanner import rigs
from simlunar.scanner.gray_code import GrayCodeOptions, gray_code_scan
from simlunar.scanner.rescan import low_contrast_pixels
from simlunar.scanner.triangulate import true_correspondences
from simlunar.study import scanner as st
from simlunar.terrain.types import Terrain

pytestmark = pytest.mark.render

N, SPACING, ORIGIN = 100, 0.02, (-1.0, 1.0)  # a 2 m x 2 m bench-top patch


def grid():
    t = Terrain(np.zeros((N, N)), np.zeros((N, N), np.float32), SPACING, ORIGIN)
    x, y = t.cell_centers()
    return np.meshgrid(x, y)


def terrain(heights, albedo=0.5):
    return Terrain(heights, np.full((N, N), albedo, np.float32), SPACING, ORIGIN)


@pytest.fixture(scope="module")
def rig():
    return rigs.moonyard_rig(proj_size=(64, 48), cam_size=(80, 60))


def capture(terr, rig, *, bsdf=None, sensor=None, rng=None, extra_lights=(), **options):
    """A RenderCapture with its CaptureOptions as keywords."""
    opts = CaptureOptions(**options)
    return RenderCapture(
        terr, rig, opts, bsdf=bsdf, sensor=sensor, rng=rng, extra_lights=extra_lights
    )


def run_study(terr, rig, *, rng=None, spp=16, max_depth=3, **options):
    """The scanner study with its options as keywords."""
    opts = st.ScannerStudyOptions(capture=CaptureOptions(spp=spp, max_depth=max_depth), **options)
    return st.run_scanner_study(st.ScannerScene(terr, rig), opts, rng=rng)


def scan(terr, rig, max_depth=3):
    cap = capture(terr, rig, max_depth=max_depth, spp=4, seed=1)
    guide = render_guide(terr, rig, spp=4)
    return cap, guide, gray_code_scan(cap, rig)


@pytest.mark.parametrize("slope", [0.0, 0.3])
def test_gray_code_depth_matches_ground_truth_on_planes(rig, slope):
    xx, _ = grid()
    _, guide, g = scan(terrain(slope * xx), rig)
    assert g.renders == 6 + 6 + 2
    ok = np.isfinite(g.depth) & guide.valid
    assert ok.mean() > 0.7  # the camera's view covers most of the projector's
    # stated tolerance: gray code resolves whole projector columns; one column spans
    # dz = z^2 / (f_p * b) of depth along a ray, and the decoded point lies within half a
    # column of the truth (plus camera-pixel averaging at stripe edges): |err| < dz everywhere,
    # median < dz / 4 (measured: median 0.16 dz, max 0.87 dz)
    truth = guide.depth[ok]
    dz = truth**2 / (rig.projector.intrinsics.fx * rig.baseline)
    err = np.abs(g.depth[ok] - truth) / dz
    assert err.max() < 1.0
    assert np.median(err) < 0.25


def test_subpixel_refinement_cuts_the_column_quantisation_on_a_tilted_plane():
    # a camera 2.5x finer than the projector resolves every stripe edge
    rig = rigs.moonyard_rig(proj_size=(64, 48), cam_size=(160, 120))
    xx, _ = grid()
    cap = capture(terrain(0.3 * xx), rig, max_depth=2, spp=4, seed=1)
    whole = gray_code_scan(cap, rig)
    sub = gray_code_scan(cap, rig, GrayCodeOptions(subpixel=True))
    # same frames, same validity: the refinement only moves points inside their projector pixel
    np.testing.assert_array_equal(sub.decode.valid, whole.decode.valid)
    pos = np.asarray(cap.scene.ground_truth().position)
    true_uv = rig.projector.project(pos.reshape(-1, 3))[0].reshape(*pos.shape[:2], 2)
    for axis in (0, 1):
        ref = np.isfinite(sub.decode.subpixel[..., axis]) & sub.decode.valid
        # measured: 94% of valid pixels refined in u, 92% in v (edges are found across
        # unreliable stripe-edge pixels; missing next to shadow and border)
        assert ref.sum() > 0.85 * sub.decode.valid.sum()
        err_whole = whole.decode.proj_uv()[..., axis][ref] - true_uv[..., axis][ref]
        err_sub = sub.decode.proj_uv()[..., axis][ref] - true_uv[..., axis][ref]
        # pixel centres: uniform quantisation, RMS 1 / sqrt(12) = 0.289 px (measured 0.278,
        # 0.277); refined: measured 0.071, 0.073 px (pixel integration and 4-spp noise)
        assert abs(np.sqrt(np.mean(err_whole**2)) - 0.289) < 0.03
        assert np.sqrt(np.mean(err_sub**2)) < 0.1


def test_camera_blur_is_the_lens_psf_on_every_frame(rig):
    flat = terrain(np.zeros((N, N)))
    sharp = capture(flat, rig, max_depth=2, spp=2, seed=4)
    soft = capture(flat, rig, max_depth=2, spp=2, seed=4, camera_blur=1.5)
    pats = np.zeros((2, 48, 64), np.float32)
    pats[0, :, ::8] = 1.0
    pats[1, ::6] = 1.0
    a, b = sharp.render(pats), soft.render(pats)
    # same scene and sampler seed: the blurred frames are the sharp ones through a Gaussian PSF
    # float32 frames: the compiled filter and SciPy's differ by at most one ulp (summation order)
    np.testing.assert_allclose(
        b, ndimage.gaussian_filter(a, (0, 1.5, 1.5), mode="nearest"), rtol=3e-7
    )
    assert soft.renders == 2
    with pytest.raises(ValueError, match="camera_blur must be >= 0"):
        capture(flat, rig, max_depth=2, spp=1, camera_blur=-1.0)


def test_projector_shadow_is_masked_not_wrong():
    # a 12 cm x 12 cm x 40 cm post; a lower projector and a wider baseline let the camera see
    # the shadow it casts
    rig = rigs.moonyard_rig(
        proj_size=(64, 48), cam_size=(80, 60), elevation=np.radians(55.0), baseline=0.5
    )
    xx, yy = grid()
    h = np.where((np.abs(xx) < 0.06) & (np.abs(yy) < 0.06), 0.4, 0.0)
    cap, guide, g = scan(terrain(h), rig)
    truth = camera_truth(cap, guide)
    frustum = true_correspondences(cap.scene.ground_truth().position, rig.projector)[0] >= 0
    shadow = truth["valid"] & frustum & ~truth["lit"]
    core = ndimage.binary_erosion(shadow, iterations=1)
    assert shadow.sum() >= 20 and core.sum() >= 5  # a real shadow in the camera's view
    # (measured: none of 38 shadow pixels decodes as valid; one-pixel rims may be half lit)
    assert not g.decode.valid[core].any()
    assert g.decode.valid[shadow].mean() <= 0.1
    # what is decoded triangulates to the right depth (bar the post's silhouette, where
    # guide pixels straddle the top and the ground)
    ok = np.isfinite(g.depth) & guide.valid
    dz = guide.depth[ok] ** 2 / (rig.projector.intrinsics.fx * rig.baseline)
    err = np.abs(g.depth[ok] - guide.depth[ok]) / dz
    assert np.percentile(err, 95) < 1.0


def test_interreflections_corrupt_coarse_bits_in_a_crater():
    # projector from the north at 50 deg elevation, camera nearly overhead: the crater's north
    # wall (45 deg slope) is lit at grazing incidence and sees the brightly lit south wall,
    # so its indirect light outweighs its direct light when the coarse stripes differ
    e = np.radians(50.0)
    proj = Projector(
        Intrinsics.from_fov(64, 48, 50.0),
        Pose.look_at((0.0, 1.7 * np.cos(e), 1.7 * np.sin(e)), (0.0, 0.0, 0.0)),
    )
    cam = Camera(
        Intrinsics.from_fov(80, 60, 50.0),
        Pose.look_at((0.3, 0.0, 1.6), (0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0)),
    )
    rig = Rig(proj, cam)
    xx, yy = grid()
    r, R = np.hypot(xx, yy), 0.35
    cone = np.where(r < R, -R * np.tan(np.radians(45.0)) * (1 - r / R), 0.0)
    res = st.interreflection_comparison(
        terrain(cone, albedo=0.9),
        rig,
        depths=(2, 3),
        spp=8,
        mask_fn=lambda p: np.hypot(p[..., 0], p[..., 1]) < 0.95 * R,
    )
    coarse = ("ber_c0", "ber_c1", "ber_r0", "ber_r1")
    direct = sum(res[2][k] for k in coarse)
    inter = sum(res[3][k] for k in coarse)
    # measured: direct 0.000, one interreflection 0.029 (mostly the row MSB)
    assert direct < 0.005
    assert inter > direct + 0.01


def test_capture_rejects_bad_input(rig):
    flat = terrain(np.zeros((N, N)))
    cap = capture(flat, rig, max_depth=2, spp=1)
    with pytest.raises(ValueError, match=r"patterns must have shape \(n, 48, 64\)"):
        cap.render(np.ones((1, 48, 63)))
    away = Camera(
        rig.camera.intrinsics,
        Pose.look_at(rig.camera.position, rig.camera.position + np.array([0, 0, 1.0])),
    )
    with pytest.raises(ValueError, match="does not see the projected area"):
        capture(flat, Rig(rig.projector, away), max_depth=2, spp=1)


def test_run_scanner_study_rows_and_modes(rig):
    xx, yy = grid()
    h = 0.05 * np.exp(-((xx - 0.1) ** 2 + yy**2) / 0.02)  # a 5 cm mound
    res = run_study(
        terrain(h),
        rig,
        modes=("gray_code", "ambiguity_enhancement", "data_reduction"),
        planners=("random",),
        budget=0.1,
        trials=1,
        metrics=("mse", "rmse"),
        rng=3,
        spp=2,
        max_depth=2,
    )
    keys = {"mode", "planner", "reconstruction", "budget", "trial", "metric", "value", "renders"}
    assert all(set(r) == keys for r in res.rows)
    assert {r["reconstruction"] for r in res.rows} == {"linear"}
    by = {(r["mode"], r["metric"]): r for r in res.rows}
    assert by[("gray_code", "mse")]["renders"] == 14
    assert {"ber_c0", "ber_r5", "valid_fraction"} <= {m for (mo, m) in by if mo == "gray_code"}
    for mode in ("gray_code", "ambiguity_enhancement", "data_reduction"):
        mse, rmse = by[(mode, "mse")]["value"], by[(mode, "rmse")]["value"]
        assert np.isclose(rmse, np.sqrt(mse))
        # depth quantised to whole projector columns, each dz = z^2 / (f_p b) deep (about 11 cm
        # at 1.6 m for this 64-column projector), has rmse dz / sqrt(12) = 0.29 dz; measured
        # 0.23 dz (gray code), 0.16 dz (data reduction)
        dz = 1.6**2 / (rig.projector.intrinsics.fx * rig.baseline)
        assert rmse < 0.35 * dz
    ae = res.scans[("ambiguity_enhancement", "random", 0)]
    assert len(ae.planned_rc) == round(0.1 * 64 * 48)
    # the dots replace gray-code depth where they were found
    hit = np.isfinite(ae.dots.depth)
    np.testing.assert_array_equal(ae.measured[hit], ae.dots.depth[hit])
    assert ae.renders == ae.dots.renders  # the gray-code scan is shared, not counted again
    with pytest.raises(ValueError, match="unknown scan mode"):
        st.ScannerStudyOptions(modes=("lidar",))
    # planner options are per planner name (random takes none); checked before rendering
    with pytest.raises(ValueError, match=r"planner_opts must map planner names \['random'\]"):
        st.ScannerStudyOptions(planners=("random",), planner_opts={"levels": 1})
    with pytest.raises(ValueError, match="use it with the ambiguity_enhancement mode"):
        run_study(terrain(h), rig, modes=("data_reduction",), planners=("low_contrast",), spp=1)


def test_scanner_study_is_seeded_and_summarised(rig):
    xx, yy = grid()
    h = 0.05 * np.exp(-((xx - 0.1) ** 2 + yy**2) / 0.02)
    kw = {"planners": ("wavelet", "random"), "metrics": ("mse",), "rng": 2, "spp": 2}
    rows = run_study(terrain(h), rig, **kw).rows
    mse = st.summarize(rows, "mse")
    assert set(mse) == {
        "gray_code",
        "ambiguity_enhancement/wavelet",
        "ambiguity_enhancement/random",
    }
    assert all(v > 0 for v in mse.values())
    assert {r["renders"] for r in rows if r["mode"] == "gray_code"} == {6 + 6 + 2}
    # same seed, same rows (noise and planner streams are all seeded)
    assert st.summarize(run_study(terrain(h), rig, **kw).rows, "mse") == mse


def test_light_traced_dot_frames_equal_path_traced_ones():
    # a bumpy bed, 12 dots: the light tracer (sparse_integrator="ptracer") and the path tracer
    # estimate the same image, so the dots' flux and centroids agree
    x, y = grid()
    bumpy = terrain(0.04 * np.sin(3 * x) * np.cos(2 * y), albedo=0.6)
    rig = rigs.moonyard_rig(proj_size=(64, 48), cam_size=(128, 96))
    path = capture(bumpy, rig, max_depth=3, spp=64, seed=2)
    light = capture(
        bumpy, rig, max_depth=3, spp=64, seed=2, sparse_integrator="ptracer", sparse_spp=16
    )
    rng = np.random.default_rng(0)
    uv = np.c_[rng.choice(np.arange(6, 58, 8), 12) + 0.5, rng.choice(np.arange(6, 42, 6), 12) + 0.5]
    uv = np.unique(uv, axis=0)
    from simlunar.scanner import dots

    pat = dots.dot_pattern((48, 64), uv)[None]
    a, b = path.render(pat)[0], light.render(pat)[0]
    assert light.renders == 1
    assert b.sum() == pytest.approx(a.sum(), rel=0.03)
    da = dots.detect_dots(a, background=0.0, rel_threshold=0.1)
    db = dots.detect_dots(b, background=0.0, rel_threshold=0.1)
    assert len(da) == len(db) >= 6
    d, _ = __import__("scipy.spatial", fromlist=["cKDTree"]).cKDTree(da.uv).query(db.uv)
    assert np.median(d) < 0.1
    # dense patterns still go to the path tracer: identical images
    stripes = np.zeros((1, 48, 64), np.float32)
    stripes[0, :, ::2] = 1.0
    np.testing.assert_array_equal(light.render(stripes), path.render(stripes))
    with pytest.raises(ValueError, match="sparse_integrator"):
        capture(bumpy, rig, sparse_integrator="bdpt")


def test_daylight_scan_adds_the_sun_by_linearity_and_still_decodes(rig):
    # the sun stays on while the projector scans (study.scan_light: sun): its image is
    # rendered once and added to every frame, which must equal (in expectation) rendering
    # projector and sun together; the black frame holds the sun and the gray code still decodes
    from simlunar.render.lights import ProjectorLight, SunLight
    from simlunar.render.scene import TerrainScene, luminance

    x, _ = grid()
    tilted = terrain(0.3 * x)
    sun = SunLight(elevation=np.radians(50.0), azimuth=np.radians(120.0), irradiance=0.5)
    day = capture(tilted, rig, max_depth=2, spp=64, seed=3, extra_lights=(sun,))
    assert day.ambient is not None and day.ambient.mean() > 0 and day.ambient_ratio > 0
    stripes = np.zeros((1, 48, 64), np.float32)
    stripes[0, :, ::4] = 1.0
    np.testing.assert_array_equal(day.render(np.zeros_like(stripes))[0], day.ambient)
    joint = TerrainScene(
        tilted,
        rig.camera,
        lights=[ProjectorLight(rig.projector, stripes[0]), sun],
        max_depth=2,
        spp=64,
        seed=3,
    )
    together = luminance(joint.render())
    added = day.render(stripes)[0]
    assert added.mean() == pytest.approx(together.mean(), rel=0.02)
    # per 5 x 5 block (Monte Carlo noise averages out; the stripes are resolved at this size)
    blocks = [ndimage.uniform_filter(a, 5)[2::5, 2::5] for a in (added, together)]
    np.testing.assert_allclose(blocks[0], blocks[1], rtol=0.1, atol=0.02 * together.max())
    # the sun-to-projector ratio the camera sees, over the pixels the projector lights
    lit = day.scene.render_patterns(np.ones_like(stripes))[0]
    on = lit > 0
    assert day.ambient_ratio == pytest.approx(day.ambient[on].mean() / lit[on].mean(), rel=1e-6)
    # the exposure is set on projector plus sun: the white frame's 99.5th percentile at 0.8
    white = day.sense(day.render(np.ones_like(stripes)))[0]
    assert np.percentile(white, EXPOSURE_PERCENTILE) == pytest.approx(0.8, rel=1e-5)
    dark = capture(tilted, rig, max_depth=2, spp=16, seed=3)
    day16 = capture(tilted, rig, max_depth=2, spp=16, seed=3, extra_lights=(sun,))
    g_dark, g_day = gray_code_scan(dark, rig), gray_code_scan(day16, rig)
    v_dark, v_day = g_dark.decode.valid.mean(), g_day.decode.valid.mean()
    assert v_day >= 0.9 * v_dark > 0.3
    both = g_dark.decode.valid & g_day.decode.valid
    same = g_dark.decode.col[both] == g_day.decode.col[both]
    assert same.mean() > 0.97


def test_low_contrast_rescans_the_least_lit_pixels_of_the_gray_code_scan(rig):
    # the planner ranks the study's own gray-code scan (no ground truth): the planned pixels
    # are low_contrast_pixels of that scan, and the fused depth is no worse than gray code
    xx, yy = grid()
    h = 0.05 * np.exp(-((xx - 0.1) ** 2 + yy**2) / 0.02)
    res = run_study(
        terrain(h),
        rig,
        modes=("gray_code", "ambiguity_enhancement"),
        planners=("low_contrast",),
        budget=0.1,
        trials=1,
        metrics=("mse",),
        rng=3,
        spp=2,
        max_depth=2,
    )
    ae = res.scans[("ambiguity_enhancement", "low_contrast", 0)]
    k = round(0.1 * 64 * 48)
    want = low_contrast_pixels(ae.coded, k, rng=0)
    # contrast values are distinct floats, so the random tie-break does not matter
    assert {tuple(p) for p in ae.planned_rc} == {tuple(p) for p in want}
    mse = {(r["mode"], r["metric"]): r["value"] for r in res.rows}
    assert mse[("ambiguity_enhancement", "mse")] <= mse[("gray_code", "mse")] * 1.05


def test_a_scan_cut_short_at_its_second_step_resumes_bit_identical(rig, monkeypatch):
    """Ctrl-C at the second sub-step (the gray-code mode, after the coded scan) keeps the
    coded scan; the rerun scans nothing again but the dot rescans, whose noise continues the
    capture's stream where the kept scan left it: the rows are those of an uninterrupted
    study. Its progress counts every frame of each scan."""
    from simlunar.imaging.sensor import SensorModel
    from simlunar.progress import reporting
    from simlunar.study.steps import MemorySteps

    xx, yy = grid()
    terr = terrain(0.05 * np.sin(6 * xx) + 0.2 * yy)
    noisy = SensorModel(full_well_e=2000.0, read_noise_e=20.0, bits=10)
    scene = st.ScannerScene(terr, rig, camera_model=noisy)
    opts = st.ScannerStudyOptions(
        modes=("gray_code", "ambiguity_enhancement"),
        planners=("random", "wavelet"),
        metrics=("mse",),
        capture=CaptureOptions(spp=2, max_depth=2),
    )
    events: list = []
    with reporting(events.append):
        clean = st.run_scanner_study(scene, opts, rng=3)
    closed = {e.path: e for e in events if e.finished}
    scan = closed[("scanner study", "gray_code scan")]
    # captured frames: a pattern and its inverse per bit (6 + 6 bits), white, black
    assert (scan.done, scan.total, scan.unit) == (26, 26, "frames")
    dots = [e for p, e in closed.items() if p[-1] == "dot frames"]
    assert len(dots) == 2 and all(e.done == e.total > 1 for e in dots)
    assert closed[("scanner study",)].done == closed[("scanner study",)].total == 4

    real_scan, real_step = st._coded_scan, st._mode_step
    scans, steps_run = [], []

    def coded_scan(o, name, capture, rig_):
        scans.append(name)
        return real_scan(o, name, capture, rig_)

    def mode_step(sensor, trials, *args):
        if not steps_run:
            steps_run.append("stopped")
            raise KeyboardInterrupt
        steps_run.append((sensor.options.mode, *trials.planners))
        return real_step(sensor, trials, *args)

    monkeypatch.setattr(st, "_coded_scan", coded_scan)
    monkeypatch.setattr(st, "_mode_step", mode_step)
    steps = MemorySteps()
    with pytest.raises(KeyboardInterrupt):
        st.run_scanner_study(scene, opts, rng=3, steps=steps)
    assert list(steps.saved) == ["coded scan gray_code"] and scans == ["gray_code"]
    scans.clear()
    resumed = st.run_scanner_study(scene, opts, rng=3, steps=steps)
    assert scans == [] and steps.loads == ["coded scan gray_code"]
    assert steps_run[1:] == [
        ("gray_code", ""),
        ("ambiguity_enhancement", "random"),
        ("ambiguity_enhancement", "wavelet"),
    ]
    assert resumed.rows == clean.rows
    # the kept scan is the one the rescans use (not a copy per step)
    ae = resumed.scans[("ambiguity_enhancement", "random", 0)]
    assert ae.coded is resumed.coded["gray_code"]


def test_scanner_guide_frames_reach_every_guided_reconstruction(rig):
    # the projector's flood frame (paper section 5: every pixel lit before a scan) is the
    # co-located frame of a sun-lit guide view; another sun is a photometric-stereo frame
    from simlunar.render import make_light
    from simlunar.render.capture import render_guide

    xx, yy = grid()
    h = 0.05 * np.exp(-((xx - 0.1) ** 2 + yy**2) / 0.02)
    terr = terrain(h)
    sun = make_light("sun", elevation=np.radians(30), azimuth=np.radians(135))
    sun2 = make_light("sun", elevation=np.radians(40), azimuth=np.radians(250))
    cap = CaptureOptions(spp=2, max_depth=2, seed=5)
    opts = st.ScannerStudyOptions(
        modes=("gray_code",), planners=("random",), metrics=("mse",), guide_light="sun",
        capture=cap, reconstructions=("linear", "smoothed", "shading"),
        guide_frames=("camera", sun2),
    )  # fmt: skip
    scene = st.ScannerScene(terr, rig, sun=sun)
    res = st.run_scanner_study(scene, opts, rng=0)
    mse = {r["reconstruction"]: r for r in res.rows if r["metric"] == "mse"}
    assert set(mse) == {"linear", "smoothed", "shading"}
    assert all(np.isfinite(r["value"]) for r in mse.values())
    assert "guide_frames" not in mse["linear"] and "guide_frames" not in mse["smoothed"]
    frames = mse["shading"]["guide_frames"].split("+")
    assert "camera" in frames and mse["shading"]["exposures"] == len(frames) >= 2
    # the frames themselves: the flood frame and the other sun, in the guide view
    recons = {n: None for n in opts.reconstructions}
    g = st.scanner_guide(scene, opts, res.guide, st.reconstruction_options(recons))
    assert g.frames == ("sun", "camera", "sun_el40_az250")
    flood = render_guide(terr, rig, light="projector", bsdf=None, max_depth=2, spp=2, seed=6)
    np.testing.assert_allclose(g.flat, flood.image)
    other = render_guide(terr, rig, light="sun", sun=sun2, max_depth=2, spp=2, seed=7)
    np.testing.assert_allclose(g.others[0][0], other.image)
    assert g.others[0][1] is None  # the rig camera is no nadir view: direction unknown
    # no guided reconstruction: no extra frame is rendered
    lin = st.reconstruction_options(("linear",))
    assert st.scanner_guide(scene, opts, res.guide, lin).frames == ("sun",)


def test_scanner_guide_frames_are_checked():
    with pytest.raises(ValueError, match="guide view's own light already"):
        st.ScannerStudyOptions(guide_light="projector", guide_frames=("camera",))
    with pytest.raises(ValueError, match="'camera' or a SunLight"):
        st.ScannerStudyOptions(guide_light="sun", guide_frames=("moon",))
    with pytest.raises(ValueError, match="listed twice"):
        st.ScannerStudyOptions(guide_light="sun", guide_frames=("camera", "camera"))


def test_rendered_fringes_lose_their_staircase_through_the_projector_optics(rig):
    # the Mitsuba path: the optics' supersampled, bilinear texture makes the decoded
    # positions fill the projector pixel evenly (the pixel grid bunches them at its steps),
    # and the error against the continuous truth falls
    from simlunar.imaging.projector_optics import ProjectorOptics
    from simlunar.scanner.codings import make_coding

    x, y = grid()
    terr = terrain(0.15 * x + 0.05 * y)
    guide = render_guide(terr, rig, spp=4)
    coding = make_coding("phase_shift", {"steps": 8, "period_px": 8.0})
    out = {}
    for name, optics in (("grid", None), ("optics", ProjectorOptics())):
        cap = capture(terr, rig, spp=16, max_depth=2, optics=optics)
        dec = coding.scan(cap, rig).decode
        h, _ = np.histogram(np.mod(dec.u[dec.valid], 1.0), bins=5, range=(0, 1))
        out[name] = (np.abs(h / h.mean() - 1).max(), coding.truth_scores(
            SimpleNamespace(decode=dec), camera_truth(cap, guide))["coord_rmse_px"])  # fmt: skip
    assert out["grid"][0] > 0.5 and out["optics"][0] < 0.15
    # (measured: 0.069 vs 0.116 px; the projection's border, where the PSF mixes the fringe
    # with the dark outside, keeps part of it)
    assert out["optics"][1] < 0.75 * out["grid"][1]
    with pytest.raises(ValueError, match="projector optics replace projector_gamma"):
        CaptureOptions(projector_gamma=2.2, optics=ProjectorOptics())
    with pytest.raises(ValueError, match="lit sparse integrator"):
        CaptureOptions(sparse_integrator="lit", optics=ProjectorOptics())
