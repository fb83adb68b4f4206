"""Parsing of unit-bearing YAML values: ``30``, ``"30 deg"``, ``"0.5 rad"``, ``"20 cm"``, ``"1/2"``.

YAML keys carry their unit as a suffix (``elevation_deg``, ``spacing_m``); a value may be a
plain number in that unit or a string with an explicit unit, which is converted to the key's
unit here, once. The library itself only ever sees SI units and radians.
"""

from __future__ import annotations

import math
import re
from fractions import Fraction

__all__ = [
    "ANGLE_UNITS",
    "LENGTH_UNITS",
    "PIXEL_UNITS",
    "UNITS_BY_SUFFIX",
    "log_spaced",
    "parse_fraction",
    "parse_quantity",
]

_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_QUANTITY = re.compile(rf"^\s*({_NUM})\s*([^\d\s].*?)?\s*$")

#: factor that converts a value in the named unit into the key's unit
ANGLE_UNITS = {"deg": 1.0, "degree": 1.0, "degrees": 1.0, "°": 1.0, "rad": 180.0 / math.pi}
LENGTH_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "km": 1000.0, "um": 1e-6}
PIXEL_UNITS = {"px": 1.0}
UNITS_BY_SUFFIX = {"deg": ANGLE_UNITS, "m": LENGTH_UNITS, "px": PIXEL_UNITS}


def parse_quantity(value, suffix: str) -> float:
    """Parse a number or a ``"<number> <unit>"`` string into the unit named by ``suffix``.

    Parameters
    ----------
    value : float, int or str
        ``30``, ``"30"``, ``"30 deg"``, ``"0.52 rad"``, ``"20 cm"``.
    suffix : str
        The key's unit suffix: ``"deg"``, ``"m"`` or ``"px"``.

    Returns
    -------
    float
        The value in the key's unit (degrees or metres).

    Raises
    ------
    ValueError
        For a non-numeric value or a unit that does not belong to the key.
    """
    units = UNITS_BY_SUFFIX[suffix]
    if isinstance(value, bool):
        raise ValueError(f"expected a number in {suffix}, got {value!r}")
    if isinstance(value, (int, float)):
        out = float(value)
    elif isinstance(value, str):
        m = _QUANTITY.match(value)
        if not m:
            raise ValueError(
                f"expected a number in {suffix} (optionally with a unit), got {value!r}"
            )
        number, unit = float(m.group(1)), (m.group(2) or suffix).strip()
        if unit not in units:
            raise ValueError(
                f"bad unit {unit!r} for a _{suffix} key (valid units: {', '.join(units)})"
            )
        out = number * units[unit]
    else:
        raise ValueError(f"expected a number in {suffix}, got {type(value).__name__}")
    if not math.isfinite(out):
        raise ValueError(f"expected a finite number, got {value!r}")
    return out


def parse_fraction(value) -> float:
    """Parse a sampling density: a number in (0, 1] or a string like ``"1/2048"``."""
    if isinstance(value, bool):
        raise ValueError(f"expected a fraction like 1/2, got {value!r}")
    if isinstance(value, str):
        try:
            out = float(Fraction(value.strip()))
        except (ValueError, ZeroDivisionError):
            raise ValueError(f"expected a fraction like 1/2 or a number, got {value!r}") from None
    elif isinstance(value, (int, float)):
        out = float(value)
    else:
        raise ValueError(f"expected a fraction like 1/2, got {type(value).__name__}")
    if not (0.0 < out <= 1.0):
        raise ValueError(f"a density must lie in (0, 1], got {value!r}")
    return out


def log_spaced(start: float, stop: float, count: int) -> list[float]:
    """``count`` densities from ``start`` to ``stop`` evenly spaced in log2 (ends included).

    ``log_spaced(1/2, 1/2048, 11) == [1/2, 1/4, ..., 1/2048]`` exactly for powers of two,
    which is the paper's protocol (section 4.1).
    """
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count}")
    if count == 1:
        return [float(start)]
    a, b = math.log2(start), math.log2(stop)
    return [float(2.0 ** (a + (b - a) * i / (count - 1))) for i in range(count)]
