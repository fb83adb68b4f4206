"""A LIDAR's hardware and the photons it gets: the lidar equation and the sun's background.

The renderer gives two radiances per receiver pixel / beam: the laser's return, for an
isotropic point laser of 1 W/sr at the receiver (``TransientOptions.laser_intensity``), and the
sun's, for a sun of irradiance 1 W/m^2 on a surface facing it (``SunLight.irradiance``). The
hardware turns them into photons (checked in tests/lidar/test_hardware.py, and per flash pixel
on a rendered plane in tests/lidar/test_scan.py):

- **Signal** per pulse. A pulse of energy ``E`` spread evenly over the lit solid angle
  ``Omega_lit`` has intensity ``E / Omega_lit``; a receiver pixel of solid angle ``Omega_pix``
  behind an aperture ``A`` collects ``L (E / Omega_lit) A Omega_pix eta / (h nu)`` photons from
  a rendered radiance ``L``. A steered beam's receiver sees the whole spot
  (``Omega_pix = Omega_lit``): ``N = L E A eta / (h nu)``, i.e. on a Lambertian target of albedo
  ``rho`` at range ``R`` and incidence ``theta`` ``N = (E / h nu) (rho / pi) cos(theta) A / R^2
  eta``. A flash lights its whole field (``Omega_lit`` = the sum of its pixels' solid angles)
  and every pixel has its own ``Omega_pix`` (:func:`pixel_solid_angles`: the exact solid angle
  of a rectangular pixel, falling about as cos^3 off axis).
- **Sun** per second: ``L_sun S_band A Omega_rx eta / (h nu)`` with ``S_band`` the solar
  spectral irradiance times the filter's bandwidth; per bin of duration ``dt``, on a
  Lambertian target: ``n = S_band cos(theta_sun) (rho / pi) Omega_rx A eta dt / (h nu)``.
  ``S`` = 0.64 W m^-2 nm^-1 at 1064 nm above the atmosphere (ASTM E490, air mass
  zero); ``Omega_rx`` is the receiver pixel's solid angle (a beam's: its receiver
  field of view, a disk of full angle ``field_rad``).

:data:`INSTRUMENTS` holds the instrument presets, read at import from ``instruments.toml``
beside this module (:func:`load_instruments`); their sources and which numbers are assumptions
are in that file's comments and in docs/lidar.md ("Instruments").
"""

from __future__ import annotations

import dataclasses
import sys
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

from simlunar.lidar.detector import DETECTOR_OPTIONS, PLANCK, DetectorOptions
from simlunar.lidar.waveform import SPEED_OF_LIGHT, PulseOptions
from simlunar.registry import Options, did_you_mean, option, shared_option

__all__ = [
    "INSTRUMENTS",
    "INSTRUMENTS_FILE",
    "LidarHardware",
    "instrument",
    "load_instruments",
    "pixel_solid_angles",
]


@dataclass(frozen=True)
class LidarHardware(Options):
    """A LIDAR's transmitter, receiver and detector (SI units)."""

    pulse_energy_j: float = option(
        10e-6,
        doc="laser energy per pulse leaving the instrument (per beam of a multi-beam laser)",
        unit="J",
        key_unit="uJ",
        gt=0,
    )
    wavelength_m: float = option(1064e-9, doc="laser wavelength", unit="m", key_unit="nm", gt=0)
    pulse_fwhm_s: float = option(
        1e-9, doc="pulse full width at half maximum (at most 10 us)", unit="s", key_unit="ns",
        gt=0, le=1e-5,
    )  # fmt: skip
    jitter_s: float = option(
        0.1e-9, doc="RMS timing jitter of detector and timing electronics (at most 10 us)",
        unit="s", key_unit="ns", ge=0, le=1e-5,
    )  # fmt: skip
    pulse_rate_hz: float = option(
        10e3, doc="pulse repetition rate (1e-3 .. 1e9)", unit="1/s", ge=1e-3, le=1e9
    )
    aperture_diameter_m: float = option(
        0.05, doc="receiver telescope / lens clear aperture", unit="m", key_unit="mm", gt=0
    )
    optics_efficiency: float = option(
        0.6, doc="receiver optics transmission (filter included)", gt=0, le=1
    )
    detector_efficiency: float = option(
        0.4, doc="photon detection efficiency of the detector", gt=0, le=1
    )
    filter_bandwidth_m: float = option(
        1e-9, doc="receiver filter bandwidth, e.g. 1e-9 for 1 nm", unit="m", key_unit="nm", gt=0
    )
    divergence_rad: float = option(
        1e-3,
        doc="full beam divergence of a steered beam (twice the 1/e^2 half-angle; below pi/2, "
        "a cone within a hemisphere)",
        unit="rad",
        key_unit="urad",
        gt=0,
        lt=np.pi / 2,
    )
    field_rad: float = option(
        1e-3,
        doc="full-angle receiver field of view: a steered beam's (a disk), or a flash "
        "receiver's across its array (its pixels take theirs from the receiver's intrinsics)",
        unit="rad",
        key_unit="urad",
        gt=0,
        lt=np.pi,
    )
    receiver_px: tuple[int, int] | None = option(
        None,
        doc="the receiver array (rows, cols) of a flash or micromirror receiver, each 1 .. "
        "8192; None: one detector (a steered beam)",
        ge=1,
        le=8192,
    )
    dark_count_rate_hz: float = shared_option(DETECTOR_OPTIONS, "dark_count_rate_hz")
    solar_irradiance_w_m2_nm: float = option(
        0.64,
        doc="solar spectral irradiance at the wavelength above the atmosphere",
        unit="W m^-2 nm^-1",
        gt=0,
    )

    @property
    def photon_energy_j(self) -> float:
        """h c / lambda (J)."""
        return PLANCK * SPEED_OF_LIGHT / self.wavelength_m

    @property
    def aperture_m2(self) -> float:
        """Receiver aperture area pi D^2 / 4 (m^2)."""
        return np.pi * self.aperture_diameter_m**2 / 4.0

    @property
    def efficiency(self) -> float:
        """Optics times detector efficiency."""
        return self.optics_efficiency * self.detector_efficiency

    @property
    def sun_band_w_m2(self) -> float:
        """Solar irradiance inside the filter band (W/m^2)."""
        return self.solar_irradiance_w_m2_nm * self.filter_bandwidth_m * 1e9

    @property
    def beam_field_sr(self) -> float:
        """Solid angle of a steered beam's receiver field, a disk of full angle ``field_rad``."""
        return 2.0 * np.pi * (1.0 - np.cos(self.field_rad / 2.0))

    @property
    def pulse(self) -> PulseOptions:
        """The pulse and jitter as :class:`PulseOptions`."""
        return PulseOptions(fwhm_s=self.pulse_fwhm_s, jitter_s=self.jitter_s)

    def lambert_signal_photons(self, range_m, albedo, incidence_rad=0.0, *, lit_sr=None,
                               pixel_sr=None):  # fmt: skip
        """Signal photons per pulse from a Lambertian target (the lidar equation).

        ``N = (E / h nu) (rho / pi) cos(theta) A / R^2 eta``, times ``pixel_sr / lit_sr`` for
        a flash pixel (None: a steered beam, whose receiver sees the whole spot).
        """
        n = (self.pulse_energy_j / self.photon_energy_j) * np.asarray(albedo) / np.pi
        n = n * np.cos(incidence_rad) * self.aperture_m2 / np.asarray(range_m) ** 2
        n = n * self.efficiency
        if lit_sr is not None or pixel_sr is not None:
            if lit_sr is None or pixel_sr is None:
                raise ValueError("a flash pixel needs both lit_sr and pixel_sr")
            n = n * np.asarray(pixel_sr) / lit_sr
        return n

    def lambert_sun_photons_per_bin(self, albedo, sun_incidence_rad, bin_s, *, field_sr=None):
        """Solar background photons per bin from a Lambertian target:
        ``S_band cos(theta_sun) (rho / pi) Omega_rx A eta dt / (h nu)`` (``field_sr`` None:
        the beam's receiver field)."""
        omega = self.beam_field_sr if field_sr is None else np.asarray(field_sr)
        s = self.sun_band_w_m2 * np.cos(sun_incidence_rad) * np.asarray(albedo) / np.pi
        return s * omega * self.aperture_m2 * self.efficiency * bin_s / self.photon_energy_j

    def detector(
        self,
        *,
        field_sr: float | None = None,
        lit_sr: float | None = None,
        laser_intensity: float = 1.0,
        sun_irradiance: float = 1.0,
        **fields,
    ) -> DetectorOptions:
        """:class:`DetectorOptions` whose photon scales turn rendered radiance into photons.

        Parameters
        ----------
        field_sr, lit_sr : float or None
            A flash pixel's solid angle (sr; the scales are for this pixel, others are scaled
            by their own, :func:`pixel_solid_angles`) and the field the pulse lights (sr).
            None, None: a steered beam (receiver field ``beam_field_sr``, spot fully seen).
        laser_intensity : float
            The rendered laser's intensity (W/sr) the histograms were made with.
        sun_irradiance : float
            The rendered sun's irradiance (W/m^2 on a surface facing it).
        **fields
            Other :class:`DetectorOptions` fields (pulses, dead time, mode ...).
        """
        per_photon = self.aperture_m2 * self.efficiency / self.photon_energy_j
        if field_sr is None and lit_sr is None:
            signal = self.pulse_energy_j * per_photon
            field = self.beam_field_sr
        elif field_sr is not None and lit_sr is not None:
            signal = self.pulse_energy_j / lit_sr * field_sr * per_photon
            field = field_sr
        else:
            raise ValueError("give both field_sr and lit_sr (a flash pixel) or neither (a beam)")
        return DetectorOptions(
            signal_photons=signal / laser_intensity,
            background_photons_per_s=self.sun_band_w_m2 * field * per_photon / sun_irradiance,
            dark_count_rate_hz=self.dark_count_rate_hz,
            **fields,
        )


def pixel_solid_angles(fx: float, fy: float, cx: float, cy: float, width: int, height: int):
    """Exact solid angle (sr) of every pixel of a pinhole receiver, (height, width) float64.

    The pixel spanning image-plane offsets ``[x0, x1] x [y0, y1]`` (in focal lengths) subtends
    ``F(x1, y1) - F(x0, y1) - F(x1, y0) + F(x0, y0)`` with ``F(x, y) = atan(x y / sqrt(1 + x^2
    + y^2))``; for small pixels that is ``Omega_0 cos^3(theta)``, ``theta`` the angle off axis.
    """
    u = (np.arange(int(width) + 1) - cx) / fx
    v = (np.arange(int(height) + 1) - cy) / fy
    big = np.arctan(u[None, :] * v[:, None] / np.sqrt(1.0 + u[None, :] ** 2 + v[:, None] ** 2))
    return big[1:, 1:] - big[1:, :-1] - big[:-1, 1:] + big[:-1, :-1]


#: the instrument presets' file, beside this module (package data)
INSTRUMENTS_FILE = "instruments.toml"


def _instrument_values(name: str, entry, where: str) -> dict[str, float]:
    """The :class:`LidarHardware` keywords of one table of an instruments file: each field at
    most once, in SI units or (an angle) as ``<field>_deg`` in degrees; a tuple field (the
    receiver array) as a list of numbers; a field left out keeps its declared default."""
    if not isinstance(entry, dict):
        raise ValueError(f"{where}: {name!r} must be a table of LidarHardware fields")
    fields = [f.name for f in dataclasses.fields(LidarHardware)]
    tuples = [f.name for f in dataclasses.fields(LidarHardware) if "tuple" in str(f.type)]
    angles = [f for f in fields if f.endswith("_rad")]
    keys = fields + [f"{a.removesuffix('_rad')}_deg" for a in angles]
    values = {}
    for key, v in entry.items():
        if key not in keys:
            raise ValueError(f"{where}: [{name}] has no field {key!r}{did_you_mean(key, keys)}")
        field = f"{key.removesuffix('_deg')}_rad" if key.endswith("_deg") else key
        if field in values:
            raise ValueError(f"{where}: [{name}] gives {field} twice (in rad and in deg)")
        if field in tuples:
            if not isinstance(v, list) or not all(_number(x) for x in v):
                raise ValueError(f"{where}: [{name}] {key} must be a list of numbers, got {v!r}")
            values[field] = tuple(v)
            continue
        if not _number(v):
            raise ValueError(f"{where}: [{name}] {key} must be a number, got {v!r}")
        values[field] = float(np.radians(v)) if key.endswith("_deg") else float(v)
    return values


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def load_instruments(path=None) -> dict[str, LidarHardware]:
    """The instrument presets of a TOML file: one table per instrument, its keys fields of
    :class:`LidarHardware` (SI units; an angle may be ``<field>_deg``, in degrees; a field
    left out keeps its declared default).

    Parameters
    ----------
    path : str or Path, optional
        Default: :data:`INSTRUMENTS_FILE` beside this module (docs/lidar.md, "Instruments":
        the presets' sources, in the file's comments too).

    Raises
    ------
    ValueError
        A table with a stray key (naming the closest field), a value that is not a number
        (a list of numbers for the receiver array), an angle given twice, or a value out of
        its field's bounds; the message names the file and the instrument.
    """
    if path is None:
        text = resources.files(__package__).joinpath(INSTRUMENTS_FILE).read_text()
        where = INSTRUMENTS_FILE
    else:
        text, where = Path(path).read_text(), str(path)
    try:
        table = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"{where}: not valid TOML: {e}") from None
    out = {}
    for name, entry in table.items():
        values = _instrument_values(name, entry, where)
        try:
            out[name] = LidarHardware(**values)
        except ValueError as e:
            raise ValueError(f"{where}: [{name}] {e}") from None
    return out


#: Instrument presets (docs/lidar.md, "Instruments": sources; ``*`` = an assumption), read from
#: :data:`INSTRUMENTS_FILE` at import.
INSTRUMENTS: dict[str, LidarHardware] = load_instruments()


def instrument(name: str, **overrides) -> LidarHardware:
    """An instrument preset of :data:`INSTRUMENTS`, with fields replaced by ``overrides``."""
    if name not in INSTRUMENTS:
        raise ValueError(
            f"unknown instrument {name!r}; valid: {', '.join(INSTRUMENTS)}"
            f"{did_you_mean(name, INSTRUMENTS)}"
        )
    return dataclasses.replace(INSTRUMENTS[name], **overrides)
