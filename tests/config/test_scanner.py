"""The shipped scanner experiment's configuration and the scanner study's config options."""

from __future__ import annotations

from pathlib import Path

import pytest

from simlunar.config.loading import load_experiment
from simlunar.config.scanner import ScannerStudyCfg
from simlunar.config.yamlio import parse_set
from simlunar.errors import ConfigError

EXPERIMENT = Path(__file__).resolve().parents[2] / "experiments" / "scanner_ambiguity.yaml"


def test_camera_blur_defaults_to_a_sharp_lens_and_rejects_negative_sigma():
    assert ScannerStudyCfg(kind="scanner").camera_blur_px == 0.0
    cfg = load_experiment(EXPERIMENT, parse_set(["study.camera_blur_px=0"]))
    assert cfg.study.camera_blur_px == 0.0
    with pytest.raises(ConfigError, match=r"study\.camera_blur_px"):
        load_experiment(EXPERIMENT, parse_set(["study.camera_blur_px=-0.5"]))
