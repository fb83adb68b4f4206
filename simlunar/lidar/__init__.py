"""Time-of-flight range sensing on arrays (NumPy / SciPy / numba only).

- :mod:`~simlunar.lidar.waveform`: time bins (round-trip optical path length), pulse and
  detector timing response applied to rendered impulse responses
- :mod:`~simlunar.lidar.detector`: expected photon counts (laser return + sun background +
  dark counts), Poisson shot noise, SPAD dead time / pile-up, Coates correction
- :mod:`~simlunar.lidar.ranging`: range extraction (peak / matched filter; first, last or
  strongest return; maximum-likelihood sub-bin position)
- :mod:`~simlunar.lidar.bounds`: the range's Cramer-Rao bound
- :mod:`~simlunar.lidar.hardware`: the instrument (link budget, sun background, presets)
- :mod:`~simlunar.lidar.apd`, :mod:`~simlunar.lidar.spad`: linear-mode APD and Geiger-mode SPAD
  receivers (excess noise; continuous-time dead time, pile-up and its correction)
- :mod:`~simlunar.lidar.gate`: the range gate from the pose and a reference plane
- :mod:`~simlunar.lidar.trajectory`: a moving platform (hover, descent)
- :mod:`~simlunar.lidar.footprint`: the beam's angular profile and footprint geometry
- :mod:`~simlunar.lidar.steering`: two-axis steering mechanics and scan time
- :mod:`~simlunar.lidar.ordering`: raster reference and nearest neighbour + 2-opt ordering
- :mod:`~simlunar.lidar.returns`: what every acquisition shares (options, rendered returns ->
  photon counts -> ranges, the :class:`~simlunar.lidar.returns.LidarScan`)
- :mod:`~simlunar.lidar.scan`: the steered-beam acquisition (altimeter, ordering, timing, a
  moving platform)
- :mod:`~simlunar.lidar.flash`: the flash and micromirror-flash acquisitions on rendered frames

The rendering of the histograms lives in :mod:`simlunar.render.transient`,
:mod:`simlunar.render.beam_capture` and :mod:`simlunar.render.flash_lidar`; this package never
imports :mod:`simlunar.render` (a scan is given its capture).
"""

from simlunar.lidar.bounds import range_crlb
from simlunar.lidar.detector import (
    DetectorOptions,
    coates_correction,
    expected_counts,
    photon_counts,
    photon_counts_dead_time,
)
from simlunar.lidar.footprint import (
    FootprintOptions,
    cone_offsets,
    footprint_radius,
    tilted_plane_spread,
)
from simlunar.lidar.ordering import (
    OrderOptions,
    exact_order,
    nearest_neighbour_order,
    order_scan,
    raster_order,
    two_opt,
)
from simlunar.lidar.ranging import RangeOptions, RangeResult, extract_ranges
from simlunar.lidar.steering import (
    ScanTiming,
    SteeringOptions,
    axis_move_time,
    move_time,
    point_times,
    pointing_angles,
    scan_timing,
)
from simlunar.lidar.waveform import (
    SPEED_OF_LIGHT,
    PulseOptions,
    TimeBins,
    pulse_kernel,
    shape_waveform,
    splat_paths,
)

__all__ = [
    "SPEED_OF_LIGHT",
    "DetectorOptions",
    "FootprintOptions",
    "OrderOptions",
    "PulseOptions",
    "RangeOptions",
    "RangeResult",
    "ScanTiming",
    "SteeringOptions",
    "TimeBins",
    "axis_move_time",
    "coates_correction",
    "cone_offsets",
    "exact_order",
    "expected_counts",
    "extract_ranges",
    "footprint_radius",
    "move_time",
    "nearest_neighbour_order",
    "order_scan",
    "photon_counts",
    "photon_counts_dead_time",
    "point_times",
    "pointing_angles",
    "pulse_kernel",
    "range_crlb",
    "raster_order",
    "scan_timing",
    "shape_waveform",
    "splat_paths",
    "tilted_plane_spread",
    "two_opt",
]
