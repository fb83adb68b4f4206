"""Guide frames: the light convention of a nadir view, and the frames rendered as the unit does."""

from __future__ import annotations

import contextlib
import dataclasses
import math

import numpy as np
import pytest

from simlunar.config import translate
from simlunar.config.schema import ExperimentCfg
from simlunar.pipeline.guide import build_guide, frame_name, grid_light
from simlunar.render.lights import sun_direction


def test_grid_light_by_hand():
    # sun due east at 30 deg: along +columns and up, no row component
    np.testing.assert_allclose(grid_light(math.radians(30), math.radians(90)),
                               [0.0, math.cos(math.radians(30)), 0.5], atol=1e-15)  # fmt: skip
    # due north: towards row 0 (rows run south), i.e. negative d_row
    np.testing.assert_allclose(grid_light(math.radians(45), 0.0), [-(0.5**0.5), 0.0, 0.5**0.5])
    # due south-west (225 deg) at 60 deg
    e, a = math.radians(60), math.radians(225)
    np.testing.assert_allclose(grid_light(e, a), [0.5 * 0.5**0.5, -0.5 * 0.5**0.5, 0.75**0.5])
    # zenith
    np.testing.assert_allclose(grid_light(math.pi / 2, 1.0), [0, 0, 1], atol=1e-15)


def test_grid_light_is_the_world_sun_in_grid_axes():
    rng = np.random.default_rng(0)
    for e, a in zip(rng.uniform(0.05, 1.5, 20), rng.uniform(-np.pi, 2 * np.pi, 20)):
        x, y, z = sun_direction(e, a)  # world: x east, y north, z up
        np.testing.assert_allclose(grid_light(e, a), [-y, x, z], atol=1e-12)
        assert np.linalg.norm(grid_light(e, a)) == pytest.approx(1.0)


def _cfg(**render):
    return ExperimentCfg.model_validate(
        {
            "name": "guide",
            "seed": 1,
            "terrain": {"preset": "aerial_1", "scale": 0.125},
            "render": {"spp": 4, "max_depth": 2, "bsdf": {"kind": "lambert"}, **render},
            "study": {"densities": [0.1], "strategies": ["grid"], "trials": 1},
        }
    )


def test_guide_frames_config():
    c = _cfg(guide_frames=["camera", {"sun": {"elevation_deg": 60, "azimuth_deg": 45}}])
    assert [frame_name(f) for f in c.render.guide_frames] == ["camera", "sun_el60_az45"]
    assert _cfg().render.guide_frames == []
    for bad, match in (
        (["camera", "camera"], "listed twice"),
        ([{"sun": {"elevation_deg": 0, "azimuth_deg": 0}}], "greater than 0"),
        ([{"sun": {"elevation_deg": 30}}], "azimuth_deg"),
    ):
        with pytest.raises(ValueError, match=match):
            _cfg(guide_frames=bad)
    with pytest.raises(ValueError, match="own light"):
        _cfg(light={"kind": "camera"}, guide_frames=["camera"])


def _scene():
    from simlunar.geometry import OrthoCamera
    from simlunar.pipeline.figure_inputs import RenderScene
    from simlunar.render.materials import make_bsdf
    from simlunar.terrain import Terrain

    n, spacing = 40, 0.5
    r, c = np.mgrid[0:n, 0:n]
    h = 0.8 * np.sin(2 * np.pi * c / 20) + 0.6 * np.cos(2 * np.pi * r / 16)
    terrain = Terrain(h, np.full((n, n), 0.3, np.float32), spacing, (0.0, 0.0))
    cam = OrthoCamera.nadir_for_grid(terrain.shape, spacing, terrain.origin, altitude=20.0)
    return RenderScene(terrain, cam, [], make_bsdf("lambert"), 4, 0, 2), h, spacing


def _lambert(h, spacing, light):
    """n . l with n = (-dh/drow, -dh/dcol, spacing) normalised, in grid axes (no shadows)."""
    g_r, g_c = np.gradient(h)
    n = np.stack([-g_r, -g_c, np.full_like(h, spacing)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.clip(n @ light, 0, None)


@pytest.mark.render
def test_frames_are_rendered_and_their_light_directions_match_the_shading():
    scene, h, spacing = _scene()
    sun2 = {"sun": {"elevation_deg": 35, "azimuth_deg": 250}}
    cfg = _cfg(light={"kind": "sun", "elevation_deg": 30, "azimuth_deg": 90},
               guide_frames=["camera", sun2], sensor=None)  # fmt: skip
    image = np.zeros(h.shape)
    timings = {}

    def develop(radiance, rng):
        return radiance / np.nanpercentile(radiance, 99)

    guide, frames = build_guide(cfg, scene, image, np.random.SeedSequence(3),
                                develop=develop, lock=contextlib.nullcontext(),
                                timings=timings)  # fmt: skip
    assert guide.frames == ("sun", "camera", "sun_el35_az250")
    assert set(frames) == {"camera", "sun_el35_az250"} and "guide_frames_s" in timings
    assert guide.spacing == 0.5
    np.testing.assert_allclose(guide.light, grid_light(math.radians(30), math.radians(90)))
    ((img2, l2),) = guide.others
    np.testing.assert_allclose(l2, grid_light(math.radians(35), math.radians(250)))
    inner = (slice(2, -2), slice(2, -2))
    # the second sun's frame is Lambert shading under the direction the guide gives for it
    corr = np.corrcoef(img2[inner].ravel(), _lambert(h, spacing, l2)[inner].ravel())[0, 1]
    mirrored = l2 * [-1, -1, 1]  # the wrong convention (sun opposite in azimuth)
    wrong = np.corrcoef(img2[inner].ravel(), _lambert(h, spacing, mirrored)[inner].ravel())[0, 1]
    assert corr > 0.95 and wrong < 0.5
    # camera-centred light: n . z, the flat frame (shading only through the slope magnitude)
    flat = guide.flat
    corr_flat = np.corrcoef(flat[inner].ravel(), _lambert(h, spacing, [0, 0, 1])[inner].ravel())
    assert corr_flat[0, 1] > 0.95


# --------------------------------------------------------------------------- flash frames


def test_flash_frame_config():
    sun = {"kind": "sun", "elevation_deg": 30, "azimuth_deg": 90}
    c = _cfg(light=sun, guide_frames=[{"flash": {"baseline_m": 5, "sun_ratio": 0.1}}])
    (f,) = c.render.guide_frames
    assert frame_name(f) == "flash" and not f.flash.daylight and f.flash.flat_field
    # ideal is the camera frame's other name: the same configuration, the same cache key
    assert _cfg(guide_frames=["ideal"]).render.guide_frames == ["camera"]
    for bad, match in (
        ([{"flash": {"baseline_m": 5}}], "one of intensity_w_sr"),
        ([{"flash": {"sun_ratio": 1, "intensity_w_sr": 3}}], "one of intensity_w_sr"),
        ([{"flash": {"energy_j": 100}}], "go together"),
        ([{"flash": {"sun_ratio": 1}}, "ideal"], "at most one co-located"),
        ([{"flash": {"sun_ratio": 1, "cutoff_deg": 89}}], "less than 85"),
    ):
        with pytest.raises(ValueError, match=match):
            _cfg(light=sun, guide_frames=bad)
    with pytest.raises(ValueError, match="need a sun"):
        _cfg(light={"kind": "camera"}, guide_frames=[{"flash": {"sun_ratio": 1.0}}])


def test_sun_ratio_sets_the_irradiance_below_the_flash():
    from simlunar.config import translate

    scene, _, _ = _scene()
    cfg = _cfg(light={"kind": "sun", "elevation_deg": 30, "azimuth_deg": 90, "irradiance": 3.0},
               guide_frames=[{"flash": {"baseline_m": 2, "sun_ratio": 0.25, "beam_exponent": 4}}])  # fmt: skip
    light = translate.flash_light(cfg.render.guide_frames[0].flash, cfg.render.light, scene.camera)
    pos, _ = light.pose(scene.camera)
    # below the flash: E = I0 / 20^2 = 0.25 x 3 W/m^2 x sin 30 deg
    assert pos[2] == pytest.approx(20.0)
    assert light.intensity / 400.0 == pytest.approx(0.25 * 3.0 * 0.5, rel=1e-12)
    e = light.irradiance(scene.camera, [pos[0], pos[1], 0.0], [0, 0, 1.0])
    assert float(e) == pytest.approx(0.375, rel=1e-12)
    # energy and exposure: I0 = Q (n + 1) / (2 pi t)
    cfg = _cfg(guide_frames=[{"flash": {"energy_j": 300, "exposure_s": 0.02, "beam_exponent": 1}}])
    light = translate.flash_light(cfg.render.guide_frames[0].flash, None, scene.camera)
    assert light.intensity == pytest.approx(300 * 2 / (2 * np.pi * 0.02), rel=1e-12)


def test_flash_geometry_in_the_grid_is_the_world_flash():
    # the flat-field's falloff on the grid (depths) equals the world irradiance of the
    # rendered light on the same surface, up to its scale
    from simlunar.pipeline.guide import flash_geometry
    from simlunar.reconstruction.flatfield import flash_falloff
    from simlunar.render.lights import FlashLight

    scene, h, spacing = _scene()
    t, cam = scene.terrain, scene.camera
    light = FlashLight(intensity=5.0, baseline=3.0, baseline_azimuth=2.0, beam_exponent=3.0)
    geo = flash_geometry(light, cam, shape=t.shape, spacing=spacing, origin=t.origin)
    depth = cam.pose.position[2] - h
    r, c = np.mgrid[0 : h.shape[0], 0 : h.shape[1]]
    pts = np.stack([t.origin[0] + (c + 0.5) * spacing, t.origin[1] - (r + 0.5) * spacing, h], -1)
    g_r, g_c = np.gradient(h, spacing)  # rows run to -y: dh/dy = -g_r
    normals = np.stack([-g_c, g_r, np.ones_like(h)], -1)
    world = light.irradiance(cam, pts, normals)
    grid = flash_falloff(depth, geo, spacing=spacing)
    inner = (slice(1, -1), slice(1, -1))  # np.gradient and the grid's mirrored edges differ
    np.testing.assert_allclose(grid[inner] / world[inner], (grid / world)[5, 5], rtol=1e-9)


def test_daylight_flash_frame_carries_both_frames_noise():
    # flash-on minus flash-off: each a full exposure with shot and read noise at the flash-on
    # frame's exposure, so the difference's variance is the sum of both frames' variances
    # (a frame whose noise were dropped, or the guide image reused as flash-off, fails this)
    from simlunar.config.render import SensorCfg
    from simlunar.pipeline.guide import flash_frame
    from simlunar.pipeline.unit import sensor_image

    cfg = SensorCfg(full_well_e=20000, read_noise_e=5, bits=16)

    def develop(rad, rng, reference=None):
        return sensor_image(rad, cfg, rng=rng, reference=reference)

    n = 250
    sun = np.full((n, n), 1.0)
    sun[:, : n // 2] = 0.5  # two levels: the exposure comes from the brighter (on) frame
    flash = np.full((n, n), 0.6)
    diff = flash_frame(flash, develop=develop, rng=7, sun_radiance=sun).astype(np.float64)
    rng = np.random.default_rng(99)
    on = develop(sun + flash, rng, sun + flash).astype(np.float64)
    off = develop(sun, rng, sun + flash).astype(np.float64)
    for half in (slice(0, n // 2), slice(n // 2, n)):
        v_sum = on[:, half].var() + off[:, half].var()
        v_one = max(on[:, half].var(), off[:, half].var())
        # 31 250 pixels: the variance's relative standard error is 0.8 %
        assert diff[:, half].var() == pytest.approx(v_sum, rel=0.04)
        assert diff[:, half].var() > 1.3 * v_one
        # the mean is the flash's signal at the flash-on exposure
        assert diff[:, half].mean() == pytest.approx(on[:, half].mean() - off[:, half].mean(),
                                                     rel=0.01)  # fmt: skip
    # flash-off is exposed at the brighter frame's exposure: its bright half sits at
    # 1 / 1.6 of flash-on's, not at the auto exposure of its own
    bright = slice(n // 2, n)
    assert off[:, bright].mean() / on[:, bright].mean() == pytest.approx(1 / 1.6, rel=0.01)
    # at night the flash alone, auto-exposed on itself
    night = flash_frame(flash, develop=develop, rng=7)
    assert night.mean() == pytest.approx(0.8, rel=0.01)


@pytest.mark.render
@pytest.mark.parametrize("daylight", [False, True])
def test_flash_frames_are_rendered_with_their_geometry(daylight):
    from simlunar.reconstruction.flatfield import flat_field

    scene, h, spacing = _scene()
    flash = {"baseline_m": 2, "sun_ratio": 1.0, "beam_exponent": 2, "daylight": daylight}
    cfg = _cfg(light={"kind": "sun", "elevation_deg": 30, "azimuth_deg": 90},
               guide_frames=[{"flash": flash}], sensor=None)  # fmt: skip
    sun_scene = dataclasses.replace(scene, lights=translate.lights(cfg.render.light, 0.0))
    from simlunar.render.scene import luminance

    radiance = luminance(sun_scene.render().image)

    def develop(rad, rng, reference=None):
        ref = rad if reference is None else reference
        return rad / np.nanpercentile(ref, 99)

    guide, frames = build_guide(cfg, scene, np.zeros(h.shape), np.random.SeedSequence(3),
                                develop=develop, lock=contextlib.nullcontext(),
                                radiance=radiance)  # fmt: skip
    # a daylight frame costs two exposures (flash-on, flash-off): the rows record both
    flat_frames = ("flash_on", "flash_off") if daylight else ("flash",)
    assert guide.frames == ("sun", *flat_frames) and set(frames) == {"flash"}
    assert guide.flat_frames == flat_frames
    assert guide.flash is not None and guide.flat is not None
    # flat-fielded on the TRUE surface, the Lambert frame of constant albedo is constant
    # (render noise only); uncorrected it carries the falloff and the incidence
    depth = scene.camera.pose.position[2] - h
    inner = (slice(2, -2), slice(2, -2))
    ff = flat_field(guide.flat, depth, guide.flash, spacing=spacing)[inner]
    raw = guide.flat[inner]
    assert ff.std() / ff.mean() < 0.03 < raw.std() / raw.mean()
