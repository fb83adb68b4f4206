"""A sampling experiment with a guided reconstruction end to end: guide frames rendered and
developed as the unit's image, every reconstruction scored on the same samples, the columns
and tables of the reconstruction axis (a test-only guided reconstruction stands in for the
library's)."""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass

import numpy as np
import pytest

from simlunar.config.schema import ExperimentCfg
from simlunar.pipeline.runner import run_experiment
from simlunar.reconstruction import RECONSTRUCTIONS, Reconstructed, reconstruct
from simlunar.registry import check_bounds, option
from simlunar.results.store import UnitCache

pytestmark = pytest.mark.render


@dataclass(frozen=True)
class _RatioOptions:
    """Test options."""

    gain: float = option(0.02, doc="height per unit of the sun / camera ratio", ge=0)

    def __post_init__(self):
        check_bounds(self)


def _ratio(points_rc, values, shape, *, guide=None, options=None):
    """Linear plus gain x (sun / camera frame - its mean): reads the image and the flat frame."""
    base = reconstruct(points_rc, values, shape)
    ratio = guide.image / np.maximum(guide.flat, 1e-3)
    extra = options.gain * (ratio - ratio.mean())
    info = {"shading_share": float(np.var(extra) / max(np.var(base), 1e-12)),
            "frames": ("sun", "camera")}  # fmt: skip
    return Reconstructed(base + extra, info)


@pytest.fixture
def ratio():
    RECONSTRUCTIONS.register("test_ratio", _ratio, _RatioOptions, guided=True)
    yield "test_ratio"
    del RECONSTRUCTIONS._entries["test_ratio"]


def _cfg(recons, frames):
    return ExperimentCfg.model_validate(
        {
            "name": "recon_axis",
            "seed": 5,
            "terrain": {"preset": "aerial_1", "scale": 0.0625},
            "render": {"spp": 4, "guide_frames": frames},
            "study": {
                "strategies": ["random", "grid", "wavelet"],
                "densities": ["1/4", "1/16", "1/64"],
                "trials": 2,
                "metrics": ["mse"],
                "reconstructions": recons,
            },
            "figures": {"enabled": False},
        }
    )


def _rows(path):
    with path.open() as f:
        return list(csv.DictReader(f))


def test_guided_reconstruction_through_the_runner(tmp_path, ratio):
    sun2 = {"sun": {"elevation_deg": 60, "azimuth_deg": 45}}
    both = _cfg(["linear", {ratio: {"gain": 0.05}}], ["camera", sun2])
    run_experiment(both, tmp_path / "both", progress=False, figures=False)
    alone = _cfg(["linear"], [])
    run_experiment(alone, tmp_path / "alone", progress=False, figures=False)

    header = (tmp_path / "both" / "results.csv").read_text().splitlines()[0]
    assert (
        header == "unit,strategy,reconstruction,guide_frames,exposures,density,k,trial,metric,value"
    )
    rows = _rows(tmp_path / "both" / "results.csv")
    lin = [r for r in rows if r["reconstruction"] == "linear"]
    rat = [r for r in rows if r["reconstruction"] == ratio]
    assert len(lin) == len(rat) == 3 * 3 * 2
    assert {(r["guide_frames"], r["exposures"]) for r in lin} == {("", "")}
    assert {(r["guide_frames"], r["exposures"]) for r in rat} == {("sun+camera", "2")}
    # adding a reconstruction (and guide frames) changes no linear number
    plain = _rows(tmp_path / "alone" / "results.csv")
    assert [r["value"] for r in plain] == [r["value"] for r in lin]
    assert (tmp_path / "alone" / "results.csv").read_text().splitlines()[0] == (
        "unit,strategy,reconstruction,density,k,trial,metric,value"
    )
    # the guided one read the frames: its errors differ
    assert [r["value"] for r in rat] != [r["value"] for r in lin]

    md = (tmp_path / "both" / "scores.md").read_text()
    assert "samples saved vs linear at equal MSE, paired by seed" in md
    assert "reconstruction=test_ratio" in md  # the existing tables, per reconstruction
    rec_csv = _rows(tmp_path / "both" / "reconstructions.csv")
    assert {r["reconstruction"] for r in rec_csv} == {ratio}
    assert {r["strategy"] for r in rec_csv} == {"random", "grid", "wavelet"}
    saved = _rows(tmp_path / "both" / "samples_saved.csv")
    assert {r["reconstruction"] for r in saved} == {"linear", ratio}
    assert not (tmp_path / "alone" / "reconstructions.csv").exists()

    prov = json.loads((tmp_path / "both" / "provenance.json").read_text())
    rec = UnitCache(tmp_path / "both").load(prov["unit_keys"][0])
    meta = rec["meta"]
    assert meta["guide_frames"] == ["sun", "camera", "sun_el60_az45"]
    share = meta["reconstruction_info"][ratio]["grid"]["shading_share"]
    assert len(share) == 3 and all(v > 0 for v in share)
    assert set(meta["reconstruction_scores"][ratio]["mse"]) == {"random", "grid", "wavelet"}
    arr = UnitCache(tmp_path / "both").load_arrays(prov["unit_keys"][0])
    assert arr["guide_camera"].shape == arr["image"].shape
    assert arr["guide_sun_el60_az45"].shape == arr["image"].shape
    assert "guide_frames_s" in rec["timings"]
