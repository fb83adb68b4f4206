"""`simlunar run` on values the documentation bounds, rules across fields and exports that
would collide: each case is refused before any render in one line, exit 2, nothing written
(the strict check of :mod:`tests.pipeline.test_bad_inputs`: stdout empty, one ``error:`` line,
no traceback, the case folder's bytes unchanged)."""

from __future__ import annotations

import pytest

from tests.pipeline.test_bad_inputs import LIDAR_GOOD, SCANNER, Case, _run_case, with_

MICRO = with_("study", {**SCANNER, "modes": ["micro_phase_shift"]})
PHASE = with_("study", {**SCANNER, "modes": ["phase_shift"]})
AMBIGUITY_MICRO = with_("study", {**SCANNER, "modes": ["ambiguity_enhancement"], "coding": "micro_phase_shift"})  # fmt: skip


SHADED = with_("study.reconstructions", ["linear", "shading"])


def guide_sun(**sun) -> dict:
    return with_("render.guide_frames", [{"sun": {"azimuth_deg": 90, **sun}}], SHADED)


def use_flat(recons, frames=None) -> dict:
    data = with_("study.reconstructions", recons)
    return data if frames is None else with_("render.guide_frames", frames, data)


def lidar(key: str, value) -> dict:
    return with_(f"study.{key}", value, LIDAR_GOOD)


CASES = [
    # documented bounds that ended in a traceback inside the unit
    Case("laser intensity 1e300 W/sr", lidar("options.transient.laser_intensity_w_sr", 1e300), "study.options.transient.laser_intensity_w_sr: Input should be less than or equal to 1000000000000000"),
    Case("laser intensity just above the cap", lidar("options.transient.laser_intensity_w_sr", 2e15), "laser_intensity_w_sr: Input should be less than or equal to"),
    # a coding's rule on the projector: the phase repeats within it
    Case("micro phase shift repeating within the projector", with_("study.options.micro_phase_opts", {"frequencies": 3, "band": 0.5, "period_px": 8}, MICRO), "study.options.micro_phase_opts: micro phase shift with 3 frequencies over a band of 0.5 at 8 px repeats every 32 px, shorter than the 256-px projector axis"),
    Case("micro phase shift repeating, scanned by ambiguity enhancement", with_("study.options.micro_phase_opts", {"frequencies": 3, "band": 0.5, "period_px": 8}, AMBIGUITY_MICRO), "study.options.micro_phase_opts: micro phase shift with 3 frequencies"),
    Case("micro phase shift repeating along rows", with_("study.options.micro_phase_opts", {"frequencies": 2, "band": 0.1, "period_px": 16, "axes": "both"}, with_("study.projector_px", [64, 320], MICRO)), "shorter than the 320-px projector axis"),
    # a rule across fields of an options class: refused by the schema (the class's own rule)
    Case("micro phase shift rays with columns only", with_("study.options.micro_phase_opts", {"method": "rays", "axes": "cols"}, MICRO), "study.options.micro_phase_opts: method 'rays' needs the row phase: use axes 'both'"),
    Case("phase shift rays with columns only", with_("study.options.phase_opts", {"method": "rays", "axes": "cols"}, PHASE), "study.options.phase_opts: method 'rays' needs the row phase"),
    # a guide sun out of its range is named as the sun's key (was "Input should be 'camera'")
    Case("guide sun at elevation 0", guide_sun(elevation_deg=0), "render.guide_frames[0].sun.elevation_deg: Input should be greater than 0"),
    Case("guide sun below the horizon", guide_sun(elevation_deg=-5), "render.guide_frames[0].sun.elevation_deg: Input should be greater than 0"),
    Case("guide sun above the zenith", guide_sun(elevation_deg=91), "render.guide_frames[0].sun.elevation_deg: Input should be less than or equal to 90"),
    Case("guide sun without an azimuth", with_("render.guide_frames", [{"sun": {"elevation_deg": 20}}], SHADED), "render.guide_frames[0].sun.azimuth_deg: Field required"),
    Case("guide frame a misspelt camera", with_("render.guide_frames", ["cam"], SHADED), "render.guide_frames[0]: Input should be 'camera'"),
    # use_flat asked for without the co-located frame it divides by (ran sun-only silently)
    Case("use_flat without a camera frame", use_flat(["linear", {"shading": {"use_flat": True}}]), "study.reconstructions: shading: use_flat: true divides by the co-located frame, but render.guide_frames has no camera frame"),
    Case("use_flat with a second sun only", use_flat([{"photoclinometry": {"use_flat": True}}], [{"sun": {"elevation_deg": 40, "azimuth_deg": 200}}]), "study.reconstructions: photoclinometry: use_flat: true"),
    Case("use_flat under a label of its own", use_flat(["linear", {"flat": {"reconstruction": "shading", "use_flat": True}}]), "study.reconstructions: flat: use_flat: true"),
    Case("use_flat in a scanner study without the flood frame", with_("study.reconstructions", [{"shading": {"use_flat": True}}], with_("study", SCANNER)), "study.reconstructions: shading: use_flat: true"),
]  # fmt: skip


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_case_exits_2_with_one_line_and_writes_nothing(case, tmp_path, monkeypatch):
    _run_case(case, tmp_path, monkeypatch)


def test_the_good_neighbours_of_the_cases_pass_the_checks():
    """Each case differs from a config that passes: a repeat-free micro phase shift, rays
    with both axes, the laser at its cap."""
    from simlunar.config.loading import validate_data
    from simlunar.pipeline.preflight import check_units
    from simlunar.pipeline.runner import expand

    for data in (
        with_("study.options.micro_phase_opts", {"method": "rays", "axes": "both"}, MICRO),
        with_("study.options.phase_opts", {"method": "plane", "axes": "cols"}, PHASE),
        lidar("options.transient.laser_intensity_w_sr", 1e15),
        guide_sun(elevation_deg=5),
        use_flat(["linear", {"shading": {"use_flat": True}}], ["camera"]),
        use_flat(["linear", {"shading": {"use_flat": False}}]),
    ):
        check_units(expand(validate_data(data)))
