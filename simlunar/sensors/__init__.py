"""Range sensors: configured objects that measure range at planned pixels (and what it cost).

``SENSORS`` names each sensor's class and options class; a new sensor is one module, its
options class and one line here (CONTRIBUTING.md shows the ideal sampler as the example).
"""

from simlunar.sensors.base import Acquisition, NothingMeasured, Sensor
from simlunar.sensors.ideal import IdealOptions, IdealSampler
from simlunar.sensors.structured_light import (
    MODES,
    ScanResult,
    StructuredLight,
    StructuredLightOptions,
)

#: sensor name -> (class, options class)
SENSORS = {
    "ideal": (IdealSampler, IdealOptions),
    "structured_light": (StructuredLight, StructuredLightOptions),
}

__all__ = [
    "MODES",
    "SENSORS",
    "Acquisition",
    "IdealOptions",
    "IdealSampler",
    "NothingMeasured",
    "ScanResult",
    "Sensor",
    "StructuredLight",
    "StructuredLightOptions",
]
