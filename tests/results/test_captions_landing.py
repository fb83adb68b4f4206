"""Landing captions name the study that ran: its rock sizes, slope, footprint and seeds."""

from simlunar.results.captions_landing import landing_cost, landing_hazards, landing_recall

STUDY = {"terrain_seeds": 8,
         "landing": {"rock_heights_m": [0.15, 0.30], "slope_deg": 5, "footprint_m": 4.0}}  # fmt: skip


def test_recall_caption_names_every_size_the_slope_and_the_seeds():
    text = landing_recall(STUDY, "shading")
    assert "15 cm, 30 cm" in text and "5 deg across a 4.0 m footprint" in text
    assert "shading reconstruction" in text and "8 terrain seed(s)" in text
    assert "95 % bootstrap interval" in text
    assert "diamonds: the mean precision" in text and "no safe site" in text


def test_cost_caption_names_the_smallest_rock_and_both_axes():
    text = landing_cost({**STUDY, "landing": {"rock_heights_m": [0.5, 0.2]}}, "linear")
    assert "taller than 20 cm" in text  # the smallest of the study's sizes
    assert "scan time (left)" in text and "laser energy it fired (right)" in text
    assert "dashed with open markers, the same plans' precision" in text
    assert "8 terrain seed(s)" in text


def test_hazard_caption_names_the_largest_rock_the_site_choice_reads():
    text = landing_hazards(STUDY)
    assert "taller than 30 cm" in text and "4.0 m square" in text and "5 deg" in text
