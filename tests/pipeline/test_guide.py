"""Guide frames: the light convention of a nadir view, and the frames rendered as the unit does."""

from __future__ import annotations

import contextlib
import math

import numpy as np
import pytest

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
