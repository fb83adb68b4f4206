"""Landing-site scores on hand-made views: a flat 16 m patch of 0.25 m pixels with known rocks
and slopes, and reconstructions that miss, shrink, shift or tilt them."""

import numpy as np
import pytest

from simlunar.metrics.landing import (
    LandingOptions,
    ground_sample_distance,
    landing_hazard_maps,
    landing_metric_names,
    landing_scores,
    object_scores,
    relief,
    slope_map,
)

S = 0.25  # pixel (m)
N = 64
# footprint 1 m = 4 px: relief window 5 px, slope half-baseline 2 px
OPTS = LandingOptions(footprint_m=1.0, site_radius_m=2.0, site_pitch_m=4.0)


def points(z):
    r, c = np.mgrid[0:N, 0:N]
    return np.stack([(c + 0.5) * S, -(r + 0.5) * S, np.asarray(z, float)], -1)


def flat():
    return np.zeros((N, N))


def with_rock(z, r, c, h, size=2):
    z = z.copy()
    z[r : r + size, c : c + size] += h
    return z


def test_gsd_and_names():
    assert ground_sample_distance(points(flat())) == pytest.approx(S)
    got = landing_scores(points(flat()), points(flat()), OPTS)
    assert list(got) == landing_metric_names(OPTS)
    assert "hazard_recall_rock_15cm" in got and "hazard_recall_slope_5deg" in got


def test_relief_of_a_rock_is_its_height():
    z = with_rock(flat(), 30, 30, 0.2)
    rel = relief(points(z), 5)
    assert rel[30, 30] == pytest.approx(0.2)
    assert rel[10, 10] == 0.0


def test_missed_rock_lowers_recall_of_its_size_only():
    truth = with_rock(flat(), 30, 30, 0.2)  # a 20 cm rock: a 15 cm hazard, not a 30 cm one
    missed = landing_scores(points(flat()), points(truth), OPTS)
    assert missed["hazard_recall_rock_15cm"] == 0.0
    assert missed["hazard_precision_rock_15cm"] == 1.0  # nothing flagged
    assert missed["hazard_recall_rock_30cm"] == 1.0  # no 30 cm rock to miss
    found = landing_scores(points(truth), points(truth), OPTS)
    assert found["hazard_recall_rock_15cm"] == 1.0
    assert found["hazard_precision_rock_15cm"] == 1.0


def test_shrunk_rock_found_at_the_small_size_not_the_large():
    truth = with_rock(flat(), 30, 30, 0.35)
    recon = with_rock(flat(), 30, 30, 0.2)
    got = landing_scores(points(recon), points(truth), OPTS)
    assert got["hazard_recall_rock_15cm"] == 1.0
    assert got["hazard_recall_rock_30cm"] == 0.0
    # height RMS: 0.15 m on 4 of 4096 pixels
    assert got["height_rms"] == pytest.approx(np.sqrt(4 * 0.15**2 / N**2))


def test_shifted_rock_is_a_miss_and_a_false_alarm():
    truth = with_rock(flat(), 30, 30, 0.4)
    recon = with_rock(flat(), 30, 40, 0.4)  # 10 px (2.5 m) off
    got = landing_scores(points(recon), points(truth), OPTS)
    assert got["hazard_recall_rock_30cm"] == 0.0
    assert got["hazard_precision_rock_30cm"] == 0.0
    near = with_rock(flat(), 30, 32, 0.4)  # touching the true rock: one pixel beside it
    got = landing_scores(points(near), points(truth), OPTS)
    assert got["hazard_recall_rock_30cm"] == 1.0


def test_object_scores_count_objects_not_pixels():
    truth = np.zeros((20, 20), bool)
    truth[2:6, 2:6] = True  # a big rock (16 px)
    truth[15, 15] = True  # a small one (1 px)
    found = np.zeros_like(truth)
    found[15, 15] = True  # the small one found
    found[10, 2] = True  # a false alarm
    assert object_scores(found, truth) == (0.5, 0.5)


def plane(slope_deg):
    _r, c = np.mgrid[0:N, 0:N]
    return np.tan(np.radians(slope_deg)) * (c + 0.5) * S


def test_slope_map_of_a_plane():
    s = slope_map(points(plane(6.0)), 2)
    assert np.nanmax(np.abs(s - 6.0)) < 1e-9
    assert np.isnan(s[0, 0]) and np.isnan(s[N // 2, 1])


def test_slope_hazard_recall_and_rms():
    truth = plane(6.0)  # steeper than 5 deg everywhere
    shallow = landing_scores(points(plane(4.0)), points(truth), OPTS)
    assert shallow["hazard_recall_slope_5deg"] == 0.0
    assert shallow["hazard_precision_slope_5deg"] == 1.0
    assert shallow["slope_rms_deg"] == pytest.approx(2.0)
    exact = landing_scores(points(truth), points(truth), OPTS)
    assert exact["hazard_recall_slope_5deg"] == 1.0
    assert exact["slope_rms_deg"] == pytest.approx(0.0, abs=1e-9)
    # a 4 deg truth with a 6 deg reconstruction: every flag false
    alarm = landing_scores(points(truth), points(plane(4.0)), OPTS)
    assert alarm["hazard_precision_slope_5deg"] == 0.0
    assert alarm["hazard_recall_slope_5deg"] == 1.0


def test_height_rms_of_an_offset():
    got = landing_scores(points(flat() + 0.1), points(flat()), OPTS)
    assert got["height_rms"] == pytest.approx(0.1)


def test_false_safe_when_the_rock_under_the_chosen_site_is_missed():
    # the site nearest the view's centre (8, -8) is chosen on a flat reconstruction; a 40 cm
    # rock sits under it in the truth
    truth = with_rock(flat(), 31, 31, 0.4)
    missed = landing_scores(points(flat()), points(truth), OPTS)
    assert missed["safe_site_called"] == 1.0
    assert missed["false_safe_site"] == 1.0
    seen = landing_scores(points(truth), points(truth), OPTS)
    assert seen["safe_site_called"] == 1.0
    assert seen["false_safe_site"] == 0.0  # it picks another, truly safe site


def test_no_safe_site_called_is_an_abort_not_a_false_safe():
    truth = with_rock(flat(), 31, 31, 0.4)
    rocky = flat()
    rocky[::3, ::3] = 0.5  # rocks everywhere in the reconstruction
    got = landing_scores(points(rocky), points(truth), OPTS)
    assert got["safe_site_called"] == 0.0
    assert got["false_safe_site"] == 0.0


def test_unknown_reconstruction_pixels_are_left_out():
    truth = flat()
    recon = flat() + 0.1
    recon[:, : N // 2] = np.nan
    pr = points(recon)
    pr[np.isnan(recon)] = np.nan
    got = landing_scores(pr, points(truth), OPTS)
    assert got["height_rms"] == pytest.approx(0.1)


@pytest.mark.parametrize(
    "kw",
    [{"rock_heights_m": ()}, {"rock_heights_m": (0.1, -0.2)}, {"rock_heights_m": (0.15, 0.151)},
     {"slope_deg": 0}, {"footprint_m": 0}],
)  # fmt: skip
def test_bad_options(kw):
    with pytest.raises(ValueError):
        LandingOptions(**kw)


def test_shapes_must_agree():
    with pytest.raises(ValueError, match="equal"):
        landing_scores(points(flat())[:10], points(flat()), OPTS)


def test_hazard_map_is_rocks_of_the_largest_size_or_slopes():
    # a 4 m footprint: a 20 cm rock tilts it by atan(0.2 / 4) = 2.9 deg, a 40 cm one by 5.7
    wide = LandingOptions(footprint_m=4.0)
    small = with_rock(flat(), 30, 30, 0.2)  # a 15 cm hazard only: not in the site's map
    assert not landing_hazard_maps(points(small), points(small), wide).any()
    big = with_rock(flat(), 30, 30, 0.4)
    m = landing_hazard_maps(points(big), points(big), wide)
    assert m[30:32, 30:32].all() and not m[:10].any()
    steep = landing_hazard_maps(points(plane(6.0)), points(plane(6.0)), OPTS)
    assert steep[2:-2, 2:-2].all() and not steep[:, :2].any()  # border: slope unknown


def test_an_abort_over_unsafe_ground_is_not_a_false_safe():
    # every site unsafe in the truth, every site called unsafe: the lander aborts
    rocky = flat()
    rocky[::3, ::3] = 0.5
    got = landing_scores(points(rocky), points(rocky), OPTS)
    assert got["safe_site_called"] == 0.0
    assert got["false_safe_site"] == 0.0


def test_the_site_is_judged_on_the_largest_rock_size():
    # a 20 cm rock under the chosen (central) site: a 15 cm hazard, but the site is judged on
    # 30 cm rocks and 5 deg slopes (the rock tilts a 4 m footprint by 2.9 deg), so it is safe
    wide = LandingOptions(footprint_m=4.0, site_radius_m=2.0, site_pitch_m=4.0)
    truth = with_rock(flat(), 31, 31, 0.2)
    got = landing_scores(points(flat()), points(truth), wide)
    assert got["hazard_recall_rock_15cm"] == 0.0  # missed, yet
    assert got["false_safe_site"] == 0.0
    taller = with_rock(flat(), 31, 31, 0.35)
    assert landing_scores(points(flat()), points(taller), wide)["false_safe_site"] == 1.0
