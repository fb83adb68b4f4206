"""The shipped scanner experiment's configuration and the scanner study's config options."""

from __future__ import annotations

from pathlib import Path

import pytest

from simlunar.config.loading import load_experiment
from simlunar.config.scanner import ScannerStudyCfg
from simlunar.config.yamlio import parse_set
from simlunar.errors import ConfigError

EXPERIMENT = Path(__file__).resolve().parents[2] / "experiments" / "scanner_ambiguity.yaml"


def test_scanner_experiment_uses_the_documented_scanner_conditions():
    cfg = load_experiment(EXPERIMENT)
    s = cfg.study
    assert s.kind == "scanner" and s.budget == 0.1 and s.planners == ["wavelet", "random"]
    assert s.camera_blur_px == 1.0
    # what the scanner study receives (config.translate): radians, library option objects
    from simlunar.config import translate

    opts = translate.scanner_options(s, cfg.render)
    assert opts.codings["gray_code"].subpixel is True and opts.coding == "gray_code"
    assert opts.capture.camera_blur == 1.0 and opts.capture.spp == cfg.render.spp
    assert opts.planner_opts["wavelet"]["feature_opts"]["levels"] == 1
    assert translate.rig_kwargs(s)["cam_fov_x"] == pytest.approx(1.0472, abs=1e-4)


def test_camera_blur_defaults_to_a_sharp_lens_and_rejects_negative_sigma():
    assert ScannerStudyCfg(kind="scanner").camera_blur_px == 0.0
    cfg = load_experiment(EXPERIMENT, parse_set(["study.camera_blur_px=0"]))
    assert cfg.study.camera_blur_px == 0.0
    with pytest.raises(ConfigError, match=r"study\.camera_blur_px"):
        load_experiment(EXPERIMENT, parse_set(["study.camera_blur_px=-0.5"]))


def test_render_guide_frames_reach_the_scanner_study():
    import numpy as np

    from simlunar.config import translate
    from simlunar.render.lights import SunLight

    sets = ["render.light={kind: sun, elevation_deg: 30, azimuth_deg: 135}",
            "study.guide_light=sun", "study.reconstructions=[linear, shading]",
            "render.guide_frames=[camera, {sun: {elevation_deg: 40, azimuth_deg: 250}}]"]  # fmt: skip
    cfg = load_experiment(EXPERIMENT, parse_set(sets))
    frames = translate.scanner_options(cfg.study, cfg.render).guide_frames
    assert frames[0] == "camera" and isinstance(frames[1], SunLight)
    assert np.degrees([frames[1].elevation, frames[1].azimuth]) == pytest.approx([40, 250])
    # the projector-lit guide view is the flood frame already
    with pytest.raises(ConfigError, match="flood frame"):
        load_experiment(EXPERIMENT, parse_set(["render.guide_frames=[camera]"]))
