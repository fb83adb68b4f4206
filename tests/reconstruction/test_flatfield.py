"""Flat-fielding a flash's frame from the rig's geometry and the samples' surface alone."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from simlunar.geometry import point_irradiance
from simlunar.reconstruction import Guide, run_reconstruction
from simlunar.reconstruction._anchor import linear_field
from simlunar.reconstruction.flatfield import FlashGeometry, flash_falloff, flat_field
from simlunar.reconstruction.shading import ShadingOptions, shading_frames
from simlunar.reconstruction.synthetic import jittered_samples, lit_terrain


def _tilted_plane(shape, spacing, depth0=50.0, tilt=(0.02, -0.03)):
    """Depths of a tilted plane 50 m below the camera: ``depth0 + a row_m + b col_m``."""
    r, c = np.mgrid[0 : shape[0], 0 : shape[1]].astype(np.float64)
    return depth0 + tilt[0] * r * spacing + tilt[1] * c * spacing


def test_flat_field_of_a_plane_under_a_point_light_is_constant():
    # a plane seen from 50 m, a flash 5 m off the camera (grid row 40, col 130, depth 0),
    # cos^3 beam: the frame falls to ~0.3 of its peak across the view; the flash's frame is
    # computed in world-like (row_m, col_m, up) coordinates by hand, independently of the
    # module's own grid set-up, and the flat-field must return one constant
    shape, s = (120, 200), 0.25
    depth = _tilted_plane(shape, s)
    geo = FlashGeometry(row=40.0, col=130.0, level=0.0, beam_exponent=3.0, cutoff=np.radians(80))
    r, c = np.mgrid[0 : shape[0], 0 : shape[1]].astype(np.float64)
    up = -depth
    pts = np.stack([r * s, c * s, up], -1)
    normal = np.array([0.02, -0.03, 1.0])  # up = -depth: n = (-d up/d row, -d up/d col, 1)
    frame = 0.6 * point_irradiance(
        pts, np.broadcast_to(normal, pts.shape), position=[40 * s, 130 * s, 0.0],
        axis=[0, 0, -1.0], intensity=2500.0, beam_exponent=3.0,
    )  # fmt: skip
    assert frame.min() / frame.max() < 0.6  # the falloff is there to remove
    # the surface known so far: the linear reconstruction of samples (a plane is exact)
    pts_rc = jittered_samples(shape, 1 / 64, rng=3)
    lin = linear_field(pts_rc, depth[pts_rc[:, 0], pts_rc[:, 1]], shape)
    out = flat_field(frame, lin.heights, geo, spacing=s)
    # inside the hull, a cell from its edge (the slopes there mix in the nearest fill outside)
    inner = ndimage.binary_erosion(lin.hull, iterations=2)
    assert out[inner].std() / out[inner].mean() < 1e-6
    # without the correction's incidence term it would not be: cos(i) varies on the tilt
    f = flash_falloff(lin.heights, geo, spacing=s)
    assert f.max() == pytest.approx(1.0) and f.min() > 0


def test_height_values_give_the_same_falloff_as_depths():
    shape, s = (40, 60), 0.5
    depth = _tilted_plane(shape, s, depth0=20.0)
    geo_d = FlashGeometry(row=10.0, col=25.0, level=1.0, beam_exponent=1.0)
    # heights = altitude - depth with the camera plane at 30 m: the light 1 m below it
    geo_h = FlashGeometry(row=10.0, col=25.0, level=29.0, beam_exponent=1.0, values="height")
    np.testing.assert_allclose(
        flash_falloff(depth, geo_d, spacing=s), flash_falloff(30.0 - depth, geo_h, spacing=s),
        rtol=1e-12,
    )  # fmt: skip


def test_flat_field_outside_the_beam_is_zero_and_options_are_checked():
    depth = np.full((30, 30), 10.0)
    geo = FlashGeometry(row=15.0, col=15.0, cutoff=np.radians(10.0))
    out = flat_field(np.ones((30, 30)), depth, geo, spacing=1.0)
    assert out[15, 15] > 0 and out[0, 0] == 0.0  # 56 deg off axis: beyond the 10 deg cutoff
    with pytest.raises(ValueError, match="axis must not be zero"):
        FlashGeometry(axis_row=0.0, axis_col=0.0, axis_up=0.0)
    with pytest.raises(ValueError, match="values"):
        FlashGeometry(values="range")
    with pytest.raises(ValueError, match="no flat"):
        Guide(np.ones((4, 4)), flash=FlashGeometry())


def test_shading_reads_the_flat_field_only_from_the_samples():
    # a flash 100 m above a 96 x 128 m terrain (1 m cells), 10 m off its centre, cos^2 beam:
    # its frame (albedo x irradiance on the TRUE surface) falls to ~0.5 at the corners.
    # Flat-fielded on the samples' linear surface, the ratio sun / flat follows the ideal
    # co-located frame's (albedo x n_up) to the flash's shading of the unresolved relief;
    # uncorrected it carries the falloff
    shape, s = (96, 128), 1.0
    scene = lit_terrain(shape, albedo_contrast=0.5, rng=2)
    depth = 100.0 - scene.heights  # the camera plane 100 m up
    geo = FlashGeometry(row=48.0, col=74.0, level=0.0, beam_exponent=2.0)
    hr, hc = np.gradient(scene.heights)
    r, c = np.mgrid[0 : shape[0], 0 : shape[1]].astype(np.float64)
    frame = scene.albedo * point_irradiance(
        np.stack([r, c, scene.heights], -1), np.stack([-hr, -hc, np.ones(shape)], -1),
        position=[48.0, 74.0, 100.0], axis=[0, 0, -1.0], beam_exponent=2.0,
    )  # fmt: skip
    guide = Guide(scene.image, flat=frame, spacing=s, flash=geo)
    pts = jittered_samples(shape, 1 / 16, rng=1)
    lin = linear_field(pts, depth[pts[:, 0], pts[:, 1]], shape)
    with pytest.raises(ValueError, match="give linear"):
        shading_frames(guide, ShadingOptions())
    ((_, ratio, _),) = shading_frames(guide, ShadingOptions(), linear=lin)
    ideal = shading_frames(Guide(scene.image, flat=scene.flat, spacing=s), ShadingOptions())
    uncorrected = shading_frames(Guide(scene.image, flat=frame, spacing=s), ShadingOptions())
    ok = ndimage.binary_erosion(lin.hull, iterations=2) & (ideal[0][1] > 0)

    def spread(r):  # median relative departure from the ideal ratio (scale-free)
        q = r[ok] / ideal[0][1][ok]
        return float(np.median(np.abs(q / np.median(q) - 1)))

    # measured: 0.028 flat-fielded, 0.21 uncorrected
    assert spread(ratio) < 0.05 and spread(ratio) < 0.25 * spread(uncorrected[0][1])
    res = run_reconstruction("shading", pts, depth[pts[:, 0], pts[:, 1]], shape, guide=guide)
    assert np.isfinite(res.heights).all()
    # the rows name the exposures the flat cost (a daylight flash: two)
    day = Guide(scene.image, flat=frame, spacing=s, flash=geo, flat_frames=("f_on", "f_off"))
    res = run_reconstruction("shading", pts, depth[pts[:, 0], pts[:, 1]], shape, guide=day)
    assert res.info["frames"].endswith("+f_on+f_off")
