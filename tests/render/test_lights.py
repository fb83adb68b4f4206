"""Light specs and their radiometry in rendered images (hand-computed radiances)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, OrthoCamera, Pose, Projector
from simlunar.render.lights import (
    LIGHTS,
    SUN_ANGULAR_DIAMETER,
    AmbientLight,
    CameraLight,
    FlashLight,
    ProjectorLight,
    SunLight,
    flash_texture,
    make_light,
    sun_direction,
)
from simlunar.render.scene import TerrainScene
from simlunar.terrain.types import Terrain


def test_sun_direction_convention():
    np.testing.assert_allclose(sun_direction(np.pi / 2, 1.234), [0, 0, 1], atol=1e-15)
    # azimuth from north (+y) clockwise towards east (+x)
    np.testing.assert_allclose(sun_direction(0.0, 0.0), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(sun_direction(0.0, np.pi / 2), [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(
        sun_direction(np.pi / 6, np.pi), [0, -np.sqrt(3) / 2, 0.5], atol=1e-15
    )


def test_solar_disk_quadrature_preserves_irradiance():
    sun = SunLight(
        np.radians(30),
        np.radians(200),
        irradiance=1361.0,
        angular_diameter=SUN_ANGULAR_DIAMETER,
        disk_samples=64,
    )
    d, e = sun.directions()
    assert d.shape == (64, 3) and e.shape == (64,)
    # a plane facing the sun receives exactly E
    assert (e * (d @ sun.direction)).sum() == pytest.approx(1361.0, rel=1e-12)
    assert e.sum() == pytest.approx(1361.0, rel=1e-5)  # mean cos over the disk: 1 - 5e-6
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)
    ang = np.arccos(np.clip(d @ sun.direction, -1, 1))
    assert ang.max() <= SUN_ANGULAR_DIAMETER / 2 + 1e-12
    # uniform in solid angle over a cap of half-angle a: mean angle^2 = a^2 / 2 (small a)
    assert np.mean(ang**2) == pytest.approx((SUN_ANGULAR_DIAMETER / 2) ** 2 / 2, rel=0.02)
    # any plane receives E cos(angle to the disk centre): the quadrature's centroid is on axis
    for n in ([0, 0, 1.0], [0.6, 0.0, 0.8], [-0.48, 0.6, 0.64]):
        n = np.asarray(n)
        assert (e * (d @ n)).sum() == pytest.approx(1361.0 * sun.direction @ n, rel=1e-12)


def test_point_sun_is_one_direction():
    d, e = SunLight(0.5, 0.2, irradiance=2.0).directions()
    assert d.shape == (1, 3) and e.tolist() == [2.0]


def test_make_light_registry():
    assert set(LIGHTS) == {"sun", "camera", "flash", "projector", "ambient"}
    sun = make_light("sun", elevation=0.3, azimuth=1.0)
    assert isinstance(sun, SunLight) and sun.irradiance == 1.0
    assert make_light("camera").intensity == 1.0
    with pytest.raises(
        ValueError, match="unknown light 'laser'; valid: ambient, camera, flash, projector, sun"
    ):
        make_light("laser")


@pytest.mark.parametrize(
    ("cls", "kw", "msg"),
    [
        (SunLight, {"elevation": -0.1, "azimuth": 0.0}, "elevation must be > 0, got -0.1"),
        (
            SunLight,
            {"elevation": 0.5, "azimuth": 0.0, "irradiance": -1.0},
            "irradiance must be >= 0, got -1.0",
        ),
        (
            SunLight,
            {"elevation": 0.5, "azimuth": 0.0, "angular_diameter": -0.1},
            "angular_diameter must be >= 0, got -0.1",
        ),
        (
            SunLight,
            {"elevation": 0.5, "azimuth": 0.0, "disk_samples": 0},
            "disk_samples must be >= 1, got 0",
        ),
        (SunLight, {"elevation": 2.0, "azimuth": 0.0}, "elevation must be <= 1.5708, got 2.0"),
        (CameraLight, {"intensity": -2.0}, "intensity must be >= 0, got -2.0"),
        (AmbientLight, {"radiance": float("nan")}, "radiance must be a finite number, got nan"),
    ],
)
def test_bad_light_parameters(cls, kw, msg):
    with pytest.raises(ValueError, match=msg):
        cls(**kw)


def test_projector_light_validation():
    proj = Projector(Intrinsics.from_fov(8, 6, 30.0), Pose(np.eye(3), np.zeros(3)))
    with pytest.raises(ValueError, match=r"pattern shape \(6, 7\) does not match"):
        ProjectorLight(proj, np.ones((6, 7)))
    with pytest.raises(ValueError, match=r"projector must be a geometry\.Projector"):
        ProjectorLight("proj", np.ones((6, 8)))
    pl = ProjectorLight(proj, np.ones((6, 8)))
    assert pl.pattern.dtype == np.float32 and not pl.pattern.flags.writeable


# --- radiometry in renders ----------------------------------------------------------------


def _plane(albedo=0.4, n=16, spacing=0.1):
    return Terrain(
        np.zeros((n, n)),
        np.full((n, n), albedo, np.float32),
        spacing,
        origin=(-n * spacing / 2, n * spacing / 2),
    )


@pytest.mark.render
@pytest.mark.parametrize("diameter", [0.0, SUN_ANGULAR_DIAMETER])
def test_lambert_plane_under_sun(mi, diameter):
    # L = albedo * E * sin(e) / pi for a horizontal Lambertian plane (E normal to the sun)
    t = _plane(albedo=0.4)
    cam = OrthoCamera.nadir_for_grid(t.shape, t.spacing, t.origin, altitude=5.0)
    e, E = np.radians(30.0), 3.0
    sun = SunLight(e, np.radians(75.0), irradiance=E, angular_diameter=diameter)
    img = TerrainScene(t, cam, lights=[sun], max_depth=2, spp=16).render()
    expected = 0.4 * E * np.sin(e) / np.pi  # = 0.19099
    # interior pixels (border pixels are only half covered by the cell-centre mesh)
    inner = img[1:-1, 1:-1]
    if diameter == 0:  # a delta light on a plane: no noise at all
        np.testing.assert_allclose(inner, expected, rtol=1e-5)
    else:
        # one of the disk's directions is picked per sample: cos varies by +-0.8 % over the
        # disk, so 16 spp leave ~0.2 % noise per pixel and ~0.01 % on the mean of 196 px
        np.testing.assert_allclose(inner, expected, rtol=0.01)
        assert inner.mean() == pytest.approx(expected, rel=5e-4)


@pytest.mark.render
def test_camera_light_inverse_square(mi):
    # point light of intensity I at the camera: L = albedo/pi * I cos(theta) / d^2, with
    # cos(theta) = H / d on a horizontal plane at depth H below the camera
    t = _plane(albedo=0.5, n=64, spacing=0.05)
    H, intensity = 2.0, 7.0
    cam = Camera(Intrinsics.from_fov(24, 24, 30.0), Pose.look_at([0.1, 0.0, H], [0.1, 0, 0]))
    scene = TerrainScene(t, cam, lights=[CameraLight(intensity)], max_depth=2, spp=64)
    img = scene.render()[..., 0]
    gt = scene.ground_truth()
    d = np.linalg.norm(gt.position - cam.position, axis=-1)
    expected = 0.5 / np.pi * intensity * H / d**3
    # box filter averages over the pixel footprint: L varies < 0.1 % across one pixel here
    np.testing.assert_allclose(img, expected, rtol=3e-3)
    assert img.max() == pytest.approx(0.5 / np.pi * intensity / H**2, rel=2e-3)


@pytest.mark.render
def test_camera_light_orthographic_is_directional(mi):
    t = _plane(albedo=0.25)
    cam = OrthoCamera.nadir_for_grid(t.shape, t.spacing, t.origin, altitude=3.0)
    img = TerrainScene(t, cam, lights=[CameraLight(2.0)], max_depth=2, spp=4).render()
    np.testing.assert_allclose(img[1:-1, 1:-1], 0.25 * 2.0 / np.pi, rtol=1e-5)


@pytest.mark.render
def test_ambient_light_white_furnace(mi):
    # a plane under a uniform sky of radiance Le reflects albedo * Le (direct light only)
    t = _plane(albedo=0.6)
    cam = OrthoCamera.nadir_for_grid(t.shape, t.spacing, t.origin, altitude=3.0)
    img = TerrainScene(t, cam, lights=[AmbientLight(1.5)], max_depth=2, spp=256).render()
    assert img[1:-1, 1:-1].mean() == pytest.approx(0.9, rel=0.01)


def _cliff_shadow(mi, diameter):
    # plateau of height h on columns 0..8, ground at 0 beyond; sun from the west (azimuth
    # 270 deg) at elevation e casts the cliff's shadow towards +x (east)
    rows, cols, s, h = 6, 64, 0.025, 1.0
    heights = np.zeros((rows, cols))
    heights[:, :9] = h
    t = Terrain(heights, np.full((rows, cols), 0.5, np.float32), s)
    cam = OrthoCamera.nadir_for_grid(t.shape, s, t.origin, altitude=5.0)
    sun = SunLight(np.radians(45.0), np.radians(270.0), angular_diameter=diameter, disk_samples=64)
    img = TerrainScene(t, cam, lights=[sun], max_depth=2, spp=64).render()[..., 0]
    return img[3], 0.5 * np.sin(np.radians(45.0)) / np.pi, 8.5 * s + h / np.tan(np.radians(45))


@pytest.mark.render
def test_finite_sun_gives_penumbra(mi):
    s = 0.025
    hard, lit, edge_x = _cliff_shadow(mi, 0.0)
    soft, _, _ = _cliff_shadow(mi, np.radians(4.0))
    x = (np.arange(64) + 0.5) * s
    ground = (x > 0.3) & (x < x[-1])  # beyond the cliff face, without the half-covered border
    frac_hard = hard[ground] / lit
    frac_soft = soft[ground] / lit
    mid = lambda f: np.sum((f > 0.1) & (f < 0.9))  # noqa: E731
    # point sun: the shadow edge crosses at most one pixel
    assert mid(frac_hard) <= 1
    # a 4 deg disk: penumbra from h/tan(e + 2 deg) to h/tan(e - 2 deg) = 0.140 m = 5.6 px
    # (10 %..90 % of the disk's visible area spans ~70 % of it: about 4 px)
    assert 3 <= mid(frac_soft) <= 6
    # both edges are centred on the shadow line of the disk centre (half the disk visible)
    for f in (frac_hard, frac_soft):
        xg = x[ground]
        k = np.flatnonzero(f >= 0.5)[0]
        x50 = np.interp(0.5, [f[k - 1], f[k]], [xg[k - 1], xg[k]])
        assert x50 == pytest.approx(edge_x, abs=s)
    # full sun far from the edge is the same with either sun (disk sampling noise: the cos
    # of the 64 directions varies by +-3.5 % at 45 deg, so ~0.5 % per pixel at 64 spp)
    np.testing.assert_allclose(frac_soft[-5:], frac_hard[-5:], rtol=0.015)
    assert frac_soft[-5:].mean() == pytest.approx(1.0, rel=5e-3)
    assert frac_soft[0] == pytest.approx(0.0, abs=1e-6)


@pytest.mark.render
def test_projector_irradiance_convention(mi):
    # projector looking straight down from depth H: E = scale * pattern / H^2 on the plane
    # (parallel to its image plane), so a Lambert plane shows L = albedo * E / pi
    t = _plane(albedo=0.8, n=64, spacing=0.05)
    cam = OrthoCamera.nadir_for_grid(t.shape, t.spacing, t.origin, altitude=4.0)
    H, scale = 2.0, 5.0
    proj = Projector(Intrinsics.from_fov(16, 12, 60.0), Pose.look_at([0, 0, H], [0, 0, 0]))
    pattern = np.full((12, 16), 0.5, np.float32)
    img = TerrainScene(
        t, cam, lights=[ProjectorLight(proj, pattern, scale=scale)], max_depth=2, spp=4
    ).render()[..., 0]
    expected = 0.8 * scale * 0.5 / H**2 / np.pi
    # lit footprint: |x| < H tan(30 deg) = 1.15 m, |y| < 0.87 m; check a central block
    np.testing.assert_allclose(img[24:40, 20:44], expected, rtol=1e-5)
    assert img[0, 0] == 0.0  # outside the projector's frustum


# --- the flash: a point emitter with falloff and a beam ----------------------------------


def test_flash_pose_and_nadir_irradiance_by_hand():
    # camera 4 m above the plane, flash 0.5 m east of it (image +x = world +x on a nadir view)
    t = _plane(n=8, spacing=0.5)
    cam = OrthoCamera.nadir_for_grid(t.shape, t.spacing, t.origin, altitude=4.0)
    f = FlashLight(intensity=7.0, baseline=0.5, beam_exponent=2.0)
    pos, axis = f.pose(cam)
    np.testing.assert_allclose(pos, [0.5, 0.0, 4.0], atol=1e-12)
    np.testing.assert_allclose(axis, [0, 0, -1], atol=1e-12)
    # directly below the flash: E = I0 / h^2; 3 m east of it: cos(theta) = cos(i) = 4 / 5
    e = f.irradiance(cam, [[0.5, 0.0, 0.0], [3.5, 0.0, 0.0]], [[0, 0, 1.0], [0, 0, 1.0]])
    np.testing.assert_allclose(e, [7.0 / 16.0, 7.0 * 0.8**2 * 0.8 / 25.0], rtol=1e-12)
    # baseline towards image down (+y device = -y world)
    pos2, _ = FlashLight(baseline=2.0, baseline_azimuth=np.pi / 2).pose(cam)
    np.testing.assert_allclose(pos2, [0.0, -2.0, 4.0], atol=1e-12)


def test_flash_texture_is_the_beam_on_the_unit_plane():
    n, cut = 3.0, np.radians(50.0)
    tex = flash_texture(n, cut, size=64)
    # texel (i, j): tan(theta) = |x| tan(cut), x the texel centre in [-1, 1]
    x = (np.arange(64) + 0.5) / 32 - 1
    r = np.hypot(x[None, :], x[:, None]) * np.tan(cut)
    c = 1 / np.sqrt(1 + r**2)
    np.testing.assert_allclose(tex, np.where(c >= np.cos(cut), c ** (n + 3), 0), rtol=1e-6)
    assert tex[0, 0] == 0 and tex[32, 32] > 0.99


@pytest.mark.render
@pytest.mark.parametrize("beam_exponent", [0.0, 4.0])
def test_flash_on_a_lambert_plane_matches_the_irradiance(mi, beam_exponent):
    # L = albedo E / pi with E = I0 cos^n(theta) cos(i) / d^2 (geometry.point_irradiance)
    t = _plane(albedo=0.5, n=64, spacing=0.1)
    cam = OrthoCamera.nadir_for_grid(t.shape, t.spacing, t.origin, altitude=3.0)
    f = FlashLight(intensity=9.0, baseline=1.0, beam_exponent=beam_exponent)
    img = TerrainScene(t, cam, lights=[f], max_depth=2, spp=64).render()[..., 0]
    r, c = np.mgrid[0:64, 0:64]
    pts = np.stack([t.origin[0] + (c + 0.5) * 0.1, t.origin[1] - (r + 0.5) * 0.1, 0 * r], -1)
    expected = 0.5 * f.irradiance(cam, pts, np.broadcast_to([0, 0, 1.0], pts.shape)) / np.pi
    inner = (slice(1, -1), slice(1, -1))
    ratio = img[inner] / expected[inner]
    # the beam texture is bilinear over 512 texels (relative curvature error < 1e-4); each
    # pixel averages the falloff over its footprint with 64 random positions (measured: mean
    # ratio 1.0000 / 1.0002, std 0.2 / 0.4 %, worst pixel 0.6 / 1.4 % for n = 0 / 4): the
    # mean within 0.1 %, each pixel within 2 %; the falloff across the plane is 2.5x (n = 0)
    assert ratio.mean() == pytest.approx(1.0, abs=1e-3)
    np.testing.assert_allclose(img[inner], expected[inner], rtol=0.02)
    assert expected[inner].max() / expected[inner].min() > 1.5


def test_a_supersampled_projector_pattern_is_a_bilinear_texture_of_its_multiple_shape():
    from simlunar.render.lights import emitter_dicts

    proj = Projector(Intrinsics.from_fov(8, 6, 30.0), Pose(np.eye(3), np.zeros(3)))
    pl = ProjectorLight(proj, np.ones((24, 32)), supersample=4)
    assert pl.pattern_shape == (24, 32)
    with pytest.raises(ValueError, match=r"pattern shape \(6, 8\) does not match .*\(24, 32\)"):
        ProjectorLight(proj, np.ones((6, 8)), supersample=4)
    with pytest.raises(ValueError, match="supersample must be a whole number >= 1"):
        ProjectorLight(proj, np.ones((6, 8)), supersample=0)
    cam = Camera(Intrinsics.from_fov(8, 6, 30.0), Pose(np.eye(3), np.zeros(3)))
    d = next(iter(emitter_dicts(pl, cam).values()))
    assert d["irradiance"]["filter_type"] == "bilinear"
    d1 = next(iter(emitter_dicts(ProjectorLight(proj, np.ones((6, 8))), cam).values()))
    assert d1["irradiance"]["filter_type"] == "nearest"


@pytest.mark.render
def test_a_supersampled_uniform_pattern_delivers_the_same_irradiance(mi):
    # the texture's resolution changes nothing but the sampling: a uniform 4x pattern lights
    # the plane as the 1x one (E = scale * pattern / H^2)
    t = _plane(albedo=0.8, n=64, spacing=0.05)
    cam = OrthoCamera.nadir_for_grid(t.shape, t.spacing, t.origin, altitude=4.0)
    proj = Projector(Intrinsics.from_fov(16, 12, 60.0), Pose.look_at([0, 0, 2.0], [0, 0, 0]))
    light = ProjectorLight(proj, np.full((48, 64), 0.5, np.float32), scale=5.0, supersample=4)
    img = TerrainScene(t, cam, lights=[light], max_depth=2, spp=4).render()[..., 0]
    np.testing.assert_allclose(img[24:40, 20:44], 0.8 * 5.0 * 0.5 / 4.0 / np.pi, rtol=1e-5)
