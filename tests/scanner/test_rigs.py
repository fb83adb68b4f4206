"""Scanner rig presets: the projector where the geometry puts it (by hand), the guide camera
co-located with it, the triangulation camera a baseline aside and verged on the target, the pixel
footprint, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner.rigs import (
    RIG_PRESETS,
    RigCamera,
    aerial_rig,
    footprint,
    make_rig,
    moonyard_rig,
    rig_preset,
)


def test_the_aerial_rig_by_hand():
    rig = aerial_rig()
    np.testing.assert_allclose(rig.projector.pose.position, [0, 0, 100], atol=1e-12)
    np.testing.assert_allclose(rig.projector.pose.rotation[:, 2], [0, 0, -1], atol=1e-12)  # nadir
    # the camera sits the baseline along the projector's x axis
    offset = rig.camera.pose.position - rig.projector.pose.position
    np.testing.assert_allclose(offset, 15.0 * rig.projector.pose.rotation[:, 0], atol=1e-12)
    # 30 deg across 1024 columns: f = 512 / tan(15 deg); a pixel at 100 m is 100 / f ~ 5.2 cm,
    # the footprint 2 * 100 * tan(15 deg) ~ 53.6 m wide (the docstring's "54 m", "5 cm")
    f = 512 / np.tan(np.radians(15))
    assert rig.projector.intrinsics.fx == pytest.approx(f)
    assert footprint(rig, 100.0) == pytest.approx(100 / f)
    assert 1024 * footprint(rig, 100.0) == pytest.approx(200 * np.tan(np.radians(15)))


def test_the_moonyard_rig_looks_at_its_target_from_70_degrees():
    target = np.array([0.3, -0.2, 0.1])
    rig = moonyard_rig(target=target)
    eye = rig.projector.pose.position
    d = eye - target
    assert np.linalg.norm(d) == pytest.approx(1.6)
    assert np.degrees(np.arcsin(d[2] / 1.6)) == pytest.approx(70.0)
    assert d[0] == pytest.approx(0.0, abs=1e-12) and d[1] > 0  # azimuth 0: from +y
    # the target on the optical axis of the projector and (verged) of the camera
    uv, _ = rig.projector.project(target)
    np.testing.assert_allclose(uv, [512, 384], atol=1e-9)
    uv, _ = rig.camera.project(target)
    np.testing.assert_allclose(uv, [512, 384], atol=1e-9)
    assert np.linalg.norm(rig.camera.pose.position - eye) == pytest.approx(0.35)


def test_the_guide_camera_is_the_projector():
    rig = moonyard_rig()
    np.testing.assert_array_equal(rig.guide.pose.position, rig.projector.pose.position)
    np.testing.assert_array_equal(rig.guide.pose.rotation, rig.projector.pose.rotation)
    assert rig.guide.intrinsics == rig.projector.intrinsics


def test_camera_options_through_a_preset():
    rig = rig_preset("moonyard", cam_size=(320, 240), cam_fov_x=np.radians(40), verge=False,
                     aperture_radius=0.01, azimuth=np.pi / 2)  # fmt: skip
    K = rig.camera.intrinsics
    assert (K.width, K.height) == (320, 240)
    assert K.fx == pytest.approx(160 / np.tan(np.radians(20)))
    np.testing.assert_allclose(rig.camera.pose.rotation, rig.projector.pose.rotation)  # parallel
    # a thin lens focuses at the camera-target distance unless told otherwise
    assert rig.camera.focus_distance == pytest.approx(np.linalg.norm(rig.camera.pose.position))
    assert rig.projector.pose.position[0] > 0  # azimuth 90 deg: the projector stands to +x
    assert set(RIG_PRESETS) == {"moonyard", "aerial"}


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"distance": 0}, "distance must be > 0 m, got 0"),
        ({"elevation": 0}, r"elevation must be in \(0, pi/2\] rad, got 0"),
        ({"elevation": 2.0}, r"elevation must be in \(0, pi/2\] rad, got 2\.0"),
        ({"baseline": 0.0}, "baseline is zero: the triangulation camera must be offset"),
    ],
)
def test_make_rig_refusals(kw, message):
    args = {"target": (0, 0, 0), "distance": 2.0, "elevation": 1.0, "baseline": 0.3,
            "proj_fov_x": 0.8}  # fmt: skip
    with pytest.raises(ValueError, match=message):
        make_rig(**{**args, **kw})


def test_preset_refusals():
    with pytest.raises(
        ValueError, match=r"^unknown rig preset 'lab'; valid: \['aerial', 'moonyard'\]$"
    ):
        rig_preset("lab")
    with pytest.raises(TypeError, match="takes the camera as cam_size, cam_fov_x"):
        aerial_rig(camera=RigCamera())
