"""figures/captions.md: a caption per figure, with units and what bands and bars mean."""

from __future__ import annotations

from simlunar.results import captions as C
from simlunar.results.figures import write_captions


def test_captions_state_units_trials_and_bands():
    text = C.error_vs_density("grad", {"trials": 7, "strategies": ["grid", "wavelet_bn"]}, 1)
    assert "in m²" in text and "mean over 7 trials" in text
    assert "±1 standard deviation over those trials" in text
    # registry labels, as in the legend, separated by semicolons (labels hold commas)
    assert "Grid; Wavelet, blue noise" in text
    assert "error bars: ±1 standard deviation" in C.scanner_errors(["mse"], 4)
    assert "4 sweep points" in C.scanner_errors(["mse"], 4)
    # all rates zero: no figure, and its caption says why
    assert C.bit_errors(1, True, 14).startswith("Not drawn: all 14 per-bit gray-code error rates")
    assert "Not drawn" not in C.bit_errors(1, False, 14)
    assert "sun elevation (deg)" in C.score_vs_sweep("mse", "render.light.elevation_deg", {})


def test_write_captions_one_section_per_figure(tmp_path):
    written = []
    write_captions(tmp_path, {"a": "first.", "b": "second."}, written)
    text = (tmp_path / "captions.md").read_text()
    assert text == "# Figure captions\n\n## a\n\nfirst.\n\n## b\n\nsecond.\n"
    assert written == [tmp_path / "captions.md"]
    write_captions(tmp_path / "none", {}, written)  # no figures: no file
    assert not (tmp_path / "none").exists()


def test_error_vs_density_caption_of_pooled_terrain_seeds():
    text = C.error_vs_density("mse", {"trials": 4, "strategies": ["grid"]}, 2, seeds=5)
    assert "mean over 5 terrain seeds × 4 trials" in text
    assert "over those 20 runs" in text and "One panel per scene or sweep point" in text
    assert "terrain seeds" not in C.error_vs_density("mse", {"trials": 4}, 1)


def test_scanner_error_bars_are_described_only_where_drawn():
    one = C.scanner_errors(["mse"], 1, n_min=1, relative=True)
    assert "a bar of one value has none" in one and "divided by the gray-code scan's" in one
    assert "±1 standard deviation over the same values" in C.scanner_errors(["mse"], 1)


def test_panel_captions_explain_the_border_bands_and_the_scale():
    text = C.panels("k/N = 1/32", "sun elevation: 5°")
    assert "Axes in metres" in text and "convex hull" in text and "nearest sample" in text
    assert "Axes in image pixels" in C.panels("", "", metres=False)


def test_the_sparse_mesh_caption_explains_dark_steps_by_the_units_own_light():
    sun = C.sparse_mesh(1250, True, threshold=0.8, light="sun")
    camera = C.sparse_mesh(1250, True, threshold=0.8, light="camera")
    assert "facing away from the sun" in sun
    # a camera-lit unit's caption must not talk about a sun it does not have
    assert "sun" not in camera.split("convex hull")[1]
    assert "camera-centred light" in camera
