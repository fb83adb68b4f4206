"""The safe-site metric on hand-made terrain."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.metrics.hazard import HazardOptions
from simlunar.metrics.safe_site import SiteOptions, grid_sites, safe_site_scores, site_fractions
from simlunar.registry import option_info


def _points(z: np.ndarray, spacing: float = 0.5) -> np.ndarray:
    rows, cols = z.shape
    y, x = np.mgrid[0:rows, 0:cols] * spacing
    return np.stack([x, -y, z], -1).astype(float)


OPTS = SiteOptions(semi_axes_m=(2.0, 2.0), pitch_m=5.0, window_px=9, baseline_px=1)


def test_grid_sites_tile_the_view_inside_its_border():
    p = _points(np.zeros((40, 40)))  # x 0 .. 19.5, y -19.5 .. 0
    c = grid_sites(p, OPTS)
    # x from 2 to 17.5: 15.5 m -> 4 centres 5 m apart, centred: 2.25, 7.25, 12.25, 17.25
    assert sorted(set(np.round(c[:, 0], 6))) == pytest.approx([2.25, 7.25, 12.25, 17.25])
    assert len(c) == 16
    with pytest.raises(ValueError, match="smaller than an ellipse"):
        grid_sites(_points(np.zeros((4, 4))), OPTS)


def test_site_fractions_by_hand():
    p = _points(np.zeros((20, 20)))
    hz = np.zeros((20, 20), bool)
    hz[4, 4] = True  # ground (2.0, -2.0)
    f = site_fractions(p, hz, np.array([[2.0, -2.0], [7.0, -7.0]]), (1.0, 1.0))
    # a disc of radius 1 m on a 0.5 m lattice holds 13 pixels, one of them flagged
    assert f == pytest.approx([1 / 13, 0.0])


def test_the_chosen_site_is_safe_only_when_the_reconstruction_sees_the_rock():
    # flat ground with a 1 m boulder in the site nearest the centre (the aim point) and a
    # 20 deg slope over another site: a reconstruction that sees the boulder chooses another
    # safe site; one that smoothed the boulder away chooses the boulder's site: unsafe
    z = np.zeros((40, 40))
    z[18:22, 18:22] = 1.0  # boulder at ground x 9-10.5, y -9 .. -10.5 (a central site)
    z[:, 30:] = np.tan(np.radians(20.0)) * (np.arange(10) * 0.5)[None, :]  # slope, east edge
    truth = _points(z)
    centres = np.array([[9.75, -9.75], [4.0, -4.0], [17.5, -10.0]])
    good = safe_site_scores(truth, truth, OPTS, centres=centres)
    assert good == {"safe_site": 1.0, "safe_site_precision": 1.0, "safe_sites_available": 1 / 3}
    blind = truth.copy()
    blind[18:22, 18:22, 2] = 0.0  # the rock missed
    bad = safe_site_scores(blind, truth, OPTS, centres=centres)
    assert bad["safe_site"] == 0.0  # chose the central site (nearest the aim), truly unsafe
    assert bad["safe_site_precision"] == pytest.approx(0.5)  # called 2 safe, 1 truly
    # a gentler slope (8 deg) is safe under 12 deg and unsafe under 5 deg (ALHAT's)
    z2 = np.tile(np.tan(np.radians(8.0)) * np.arange(40) * 0.5, (40, 1))
    t2 = _points(z2)
    c2 = np.array([[10.0, -10.0]])
    assert safe_site_scores(t2, t2, OPTS, centres=c2)["safe_sites_available"] == 1.0
    strict = SiteOptions(slope_deg=5.0, semi_axes_m=(2.0, 2.0), window_px=9, baseline_px=1)
    assert safe_site_scores(t2, t2, strict, centres=c2)["safe_sites_available"] == 0.0


def test_bad_site_options():
    with pytest.raises(ValueError, match="semi_axes_m"):
        SiteOptions(semi_axes_m=(0.0, 1.0))
    with pytest.raises(ValueError, match=r"max_hazard_fraction must be < 1, got 1\.0"):
        SiteOptions(max_hazard_fraction=1.0)
    with pytest.raises(ValueError, match=r"slope_deg must be < 90, got 95\.0"):
        SiteOptions(slope_deg=95.0)
    with pytest.raises(ValueError, match="window_px must be odd, got 16"):
        SiteOptions(window_px=16)


def test_the_hazard_thresholds_are_declared_once():
    # the landing question's thresholds are the hazard map's options: same doc, unit and
    # bounds (the slope's default is each class's own: 12 deg here, 15 deg for a hazard map)
    site, hazard = option_info(SiteOptions), option_info(HazardOptions)
    assert site["rock_height_m"] == hazard["relief_m"]
    assert site["window_px"] == hazard["window_px"]
    assert site["baseline_px"] == hazard["baseline_px"]
    assert {**site["slope_deg"], "default": None} == {**hazard["slope_deg"], "default": None}
    assert (site["slope_deg"]["default"], hazard["slope_deg"]["default"]) == (12.0, 15.0)
    assert SiteOptions().hazard == HazardOptions(slope_deg=12.0)
