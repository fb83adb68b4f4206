"""The plain binary code: the projector's columns (rows) numbered by their binary digits, one
pattern per bit, read by the gray code's decoder (:mod:`simlunar.scanner.gray_code`).

The binary code is the textbook counter-example to the gray code (Inokuchi, Sato & Matsuda,
ICPR 1984; Salvi, Pages & Batlle, Pattern Recognition 37, 2004, section 3.1): at a boundary
between columns ``c`` and ``c + 1`` every bit below the highest changing one flips at once
(up to all ``n`` at ``2**(n-1) - 1 | 2**(n-1)``), so a camera pixel straddling that boundary can
read any mix of the two words, a gross error of up to half the projector; the gray code
flips one bit per boundary, so the same pixel is off by at most one column. Same stack layout,
frame count, thresholds and options as the gray code.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.scanner.bitcodes import BitCode
from simlunar.scanner.gray_code import GrayCodeOptions

__all__ = ["BINARY", "BinaryCodeOptions", "binary"]


def binary(values) -> np.ndarray:
    """The binary code word of an index: the index itself."""
    return np.asarray(values, dtype=np.int64)


#: the plain binary code
BINARY = BitCode("binary", binary)


@dataclass(frozen=True)
class BinaryCodeOptions(GrayCodeOptions):
    """Options of the plain binary code: the gray code's (:class:`GrayCodeOptions`) with the
    binary code's words."""

    code: BitCode = BINARY
