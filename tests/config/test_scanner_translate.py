"""The scanner study's configuration -> library options (simlunar/config/scanner_translate.py):
radians, metres and the library's option objects, from the shipped scanner experiment."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from simlunar.config import scanner_translate
from simlunar.config.loading import load_experiment
from simlunar.config.yamlio import parse_set
from simlunar.errors import ConfigError
from simlunar.render.lights import SunLight

EXPERIMENT = Path(__file__).resolve().parents[2] / "experiments" / "scanner_ambiguity.yaml"


def test_scanner_experiment_uses_the_documented_scanner_conditions():
    cfg = load_experiment(EXPERIMENT)
    s = cfg.study
    assert s.kind == "scanner" and s.budget == 0.1 and s.planners == ["wavelet", "random"]
    assert s.camera_blur_px == 1.0
    # what the scanner study receives: radians, library option objects
    opts = scanner_translate.scanner_options(s, cfg.render)
    assert opts.codings["gray_code"].subpixel is True and opts.coding == "gray_code"
    assert opts.capture.camera_blur == 1.0 and opts.capture.spp == cfg.render.spp
    assert opts.planner_opts["wavelet"]["feature_opts"]["levels"] == 1
    assert scanner_translate.rig_kwargs(s)["cam_fov_x"] == pytest.approx(1.0472, abs=1e-4)


def test_render_guide_frames_reach_the_scanner_study():
    sets = ["render.light={kind: sun, elevation_deg: 30, azimuth_deg: 135}",
            "study.guide_light=sun", "study.reconstructions=[linear, shading]",
            "render.guide_frames=[camera, {sun: {elevation_deg: 40, azimuth_deg: 250}}]"]  # fmt: skip
    cfg = load_experiment(EXPERIMENT, parse_set(sets))
    frames = scanner_translate.scanner_options(cfg.study, cfg.render).guide_frames
    assert frames[0] == "camera" and isinstance(frames[1], SunLight)
    assert np.degrees([frames[1].elevation, frames[1].azimuth]) == pytest.approx([40, 250])
    # the projector-lit guide view is the flood frame already
    with pytest.raises(ConfigError, match="flood frame"):
        load_experiment(EXPERIMENT, parse_set(["render.guide_frames=[camera]"]))
