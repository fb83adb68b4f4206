"""The hardware link budget: the lidar equation, the sun's background, pixel solid angles."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simlunar.lidar.hardware import (
    INSTRUMENTS,
    LidarHardware,
    instrument,
    load_instruments,
    pixel_solid_angles,
)

HNU_1064 = 6.62607015e-34 * 299_792_458.0 / 1064e-9  # 1.8670e-19 J


def test_lidar_equation_by_hand():
    # 10 uJ, 5 cm aperture (1.9635e-3 m^2), 0.6 x 0.4 efficiency, albedo 0.12 at 50 m, 30 deg:
    # N = (1e-5 / 1.8670e-19) (0.12 / pi) cos 30 x 1.9635e-3 / 2500 x 0.24 = 3.3375e5
    hw = LidarHardware()
    assert hw.photon_energy_j == pytest.approx(1.8670e-19, rel=1e-4)
    n = hw.lambert_signal_photons(50.0, 0.12, np.radians(30.0))
    assert n == pytest.approx(3.3375e5, rel=1e-3)
    # the renderer's radiance of that target under a 1 W/sr point laser is
    # (rho / pi) cos(theta) / R^2; the detector's scale turns it into the same photons
    radiance = 0.12 / np.pi * np.cos(np.radians(30.0)) / 50.0**2
    assert radiance * hw.detector().signal_photons == pytest.approx(n, rel=1e-12)
    # a laser rendered at 5 W/sr: the scale is per unit of that render
    assert 5 * radiance * hw.detector(laser_intensity=5.0).signal_photons == pytest.approx(n)


def test_solar_background_by_hand():
    # S = 0.64 W m^-2 nm^-1 at 1064 nm through 1 nm; albedo 0.12, sun 60 deg from the normal,
    # 1 mrad receiver field (7.854e-7 sr), 1 ns bin:
    # n = 0.64 x 0.5 x 0.0382 x 7.854e-7 x 1.9635e-3 x 0.24 x 1e-9 / 1.867e-19 = 2.423e-2
    hw = LidarHardware()
    assert hw.sun_band_w_m2 == pytest.approx(0.64)
    assert hw.beam_field_sr == pytest.approx(np.pi * 0.5e-3**2, rel=1e-6)
    n = hw.lambert_sun_photons_per_bin(0.12, np.radians(60.0), 1e-9)
    assert n == pytest.approx(2.423e-2, rel=2e-3)
    # through the renderer: sun radiance (rho / pi) cos(theta_sun) x irradiance
    det = hw.detector(sun_irradiance=2.0)
    rendered = 2.0 * 0.12 / np.pi * 0.5
    assert rendered * det.background_photons_per_s * 1e-9 == pytest.approx(n, rel=1e-12)


def test_flash_pixel_shares_the_pulse_by_solid_angle():
    hw = LidarHardware()
    det = hw.detector(field_sr=1e-6, lit_sr=1e-2)
    assert det.signal_photons == pytest.approx(hw.detector().signal_photons * 1e-4)
    n = hw.lambert_signal_photons(50.0, 0.12, lit_sr=1e-2, pixel_sr=1e-6)
    assert n == pytest.approx(hw.lambert_signal_photons(50.0, 0.12) * 1e-4)
    with pytest.raises(ValueError, match="both"):
        hw.detector(field_sr=1e-6)


def test_pixel_solid_angles_are_exact_and_fall_as_cos3():
    # a 40 deg square field of 128 x 128 pixels: the pixels tile the field's solid angle,
    # 4 atan(t^2 / sqrt(1 + 2 t^2)) with t = tan 20 deg
    f = 64 / np.tan(np.radians(20.0))
    om = pixel_solid_angles(f, f, 64.0, 64.0, 128, 128)
    t = np.tan(np.radians(20.0))
    assert om.sum() == pytest.approx(4 * np.arctan(t**2 / np.sqrt(1 + 2 * t**2)), rel=1e-12)
    # the corner pixel: cos^3 of its centre's angle off axis (about 27.3 deg), 1.4x dimmer
    x = y = 63.5 / f
    cos = 1 / np.sqrt(1 + x**2 + y**2)
    assert om[0, 0] / om[63, 63] == pytest.approx(cos**3, rel=1e-3)
    assert 1.38 < om[63, 63] / om[0, 0] < 1.45


def test_presets_and_overrides():
    assert set(INSTRUMENTS) == {
        "lola_beam",
        "alhat_flash",
        "rover_mast_scanner",
        "micromirror_flash",
    }
    lola = instrument("lola_beam", pulse_rate_hz=10e3)
    assert lola.pulse_energy_j == pytest.approx(0.54e-3) and lola.pulse_rate_hz == 1e4
    assert lola.aperture_m2 == pytest.approx(np.pi * 0.07**2)
    with pytest.raises(ValueError, match="unknown instrument 'lola'; valid: lola_beam") as err:
        instrument("lola")
    assert str(err.value).endswith("(did you mean 'lola_beam'?)")
    with pytest.raises(ValueError, match="optics_efficiency must be <= 1"):
        dataclasses.replace(lola, optics_efficiency=1.2)
    with pytest.raises(ValueError, match=r"pulse_energy_j must be > 0, got 0\.0"):
        LidarHardware(pulse_energy_j=0.0)


def test_the_presets_file_holds_the_published_numbers():
    """Hand-picked values of instruments.toml, with their sources (docs/lidar.md)."""
    lola = INSTRUMENTS["lola_beam"]
    # LOLA, Smith et al. 2010 (Space Sci. Rev. 150): 2.7 mJ split into 5 beams at 28 Hz,
    # a 14 cm telescope, 100 urad beams, 1064 nm
    assert lola.pulse_energy_j == 2.7e-3 / 5 and lola.pulse_rate_hz == 28.0
    assert lola.aperture_diameter_m == 0.14 and lola.divergence_rad == 100e-6
    assert lola.wavelength_m == 1064e-9 and lola.field_rad == 400e-6
    # the ALHAT-class flash's 1 deg field (an assumption, given in degrees in the file)
    alhat = INSTRUMENTS["alhat_flash"]
    assert alhat.field_rad == alhat.divergence_rad == np.radians(1.0) == 0.017453292519943295
    assert alhat.pulse_energy_j == 30e-3 and alhat.detector_efficiency == 0.5
    # the micromirror flash: optics 0.6 x the device's throughput 0.65 = 0.39, a 40 deg field
    mm = INSTRUMENTS["micromirror_flash"]
    assert mm.optics_efficiency == 0.39 and mm.divergence_rad == np.radians(40.0)
    assert INSTRUMENTS["rover_mast_scanner"].dark_count_rate_hz == 100.0
    # ASTM E490 (air mass zero): 0.64 W m^-2 nm^-1 at 1064 nm, in every preset
    assert {hw.solar_irradiance_w_m2_nm for hw in INSTRUMENTS.values()} == {0.64}
    # every number a float (an int from the file converted), the receiver arrays int pairs
    for hw in INSTRUMENTS.values():
        for k, v in vars(hw).items():
            if k == "receiver_px":
                assert v is None or (len(v) == 2 and all(type(x) is int for x in v))
            else:
                assert type(v) is float, k


GOOD = """
[probe]
pulse_energy_j = 1e-3
wavelength_m = 1064e-9
pulse_fwhm_s = 1e-9
jitter_s = 0.1e-9
pulse_rate_hz = 30
aperture_diameter_m = 0.05
optics_efficiency = 0.5
detector_efficiency = 0.5
filter_bandwidth_m = 1e-9
divergence_deg = 2.0
field_rad = 1e-3
dark_count_rate_hz = 0.0
solar_irradiance_w_m2_nm = 0.64
"""


def test_an_instruments_file_round_trips_its_values(tmp_path):
    path = tmp_path / "instruments.toml"
    path.write_text(GOOD)
    hw = load_instruments(path)["probe"]
    assert hw.divergence_rad == np.radians(2.0) and hw.pulse_rate_hz == 30.0
    assert dataclasses.replace(hw, pulse_energy_j=1e-3) == hw
    assert hw.receiver_px is None  # one detector


def test_an_instrument_left_out_field_takes_its_declared_default(tmp_path):
    # a field added to LidarHardware needs no edit of every preset: a preset without it keeps
    # the declared default (and a preset that gives it, its own value)
    path = tmp_path / "instruments.toml"
    path.write_text(GOOD.replace("jitter_s = 0.1e-9\n", "") + "receiver_px = [128, 64]\n")
    hw = load_instruments(path)["probe"]
    assert hw.jitter_s == LidarHardware().jitter_s
    assert hw.receiver_px == (128, 64)


def test_the_flash_presets_carry_their_receiver_array_and_field():
    alhat = INSTRUMENTS["alhat_flash"]
    assert alhat.receiver_px == (128, 128) and alhat.field_rad == pytest.approx(np.radians(1.0))
    assert INSTRUMENTS["lola_beam"].receiver_px is None


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda t: t.replace("pulse_rate_hz", "pulse_rate"),
            r"\[probe\] has no field 'pulse_rate' \(did you mean 'pulse_rate_hz'\?\)",
        ),
        (
            lambda t: t + "receiver_px = [128, 0]\n",
            r"\[probe\] receiver_px must be each >= 1, got \(128, 0\)",
        ),
        (
            lambda t: t + "receiver_px = 128\n",
            r"\[probe\] receiver_px must be a list of numbers, got 128",
        ),
        (
            lambda t: t.replace("divergence_deg = 2.0", "divergence_deg = 90.0"),
            r"\[probe\] divergence_rad must be < 1\.5708",
        ),
        (
            lambda t: t.replace("optics_efficiency = 0.5", "optics_efficiency = 1.5"),
            r"\[probe\] optics_efficiency must be <= 1, got 1\.5",
        ),
        (
            lambda t: t.replace("field_rad = 1e-3", 'field_rad = "1 mrad"'),
            r"\[probe\] field_rad must be a number, got '1 mrad'",
        ),
        (
            lambda t: t + "divergence_rad = 1e-3\n",
            r"\[probe\] gives divergence_rad twice \(in rad and in deg\)",
        ),
        (lambda t: "probe = 3\n", "'probe' must be a table of LidarHardware fields"),
        (lambda t: t.replace("[probe]", "[probe"), "not valid TOML"),
    ],
)
def test_a_bad_instruments_entry_is_named(tmp_path, edit, message):
    path = tmp_path / "instruments.toml"
    path.write_text(edit(GOOD))
    with pytest.raises(ValueError, match=message):
        load_instruments(path)


def test_with_hardware_sets_every_option_of_hardware_sets_and_nothing_else():
    from simlunar.lidar.flash import FlashOptions
    from simlunar.lidar.scan import (
        HARDWARE_SETS,
        SteeredBeamOptions,
        generic_hardware,
        with_hardware,
    )

    hw = INSTRUMENTS["lola_beam"]
    beam = with_hardware(SteeredBeamOptions(window_m=9.0), hw)
    assert beam.hardware is hw and beam.window_m == 9.0
    assert (beam.pulse.fwhm_s, beam.pulse.jitter_s) == (hw.pulse_fwhm_s, hw.jitter_s)
    assert beam.footprint.divergence_rad == hw.divergence_rad == 100e-6
    assert beam.steering.pulse_rate_hz == hw.pulse_rate_hz == 28.0
    assert beam.steering.max_rate_rad_s == SteeredBeamOptions().steering.max_rate_rad_s
    flash = with_hardware(FlashOptions(), INSTRUMENTS["alhat_flash"])
    assert flash.pulse_rate_hz == 30.0 and flash.pulse.fwhm_s == 6e-9
    # the generic hardware reads the same options back (and its receiver sees the beam)
    back = generic_hardware(beam)
    for k in HARDWARE_SETS:
        assert getattr(back, k) == getattr(hw, k), k
    assert back.field_rad == back.divergence_rad
    assert generic_hardware(FlashOptions()).divergence_rad == LidarHardware().divergence_rad
