"""Range sensors: configured objects that measure range at planned pixels (and what it cost).

``SENSORS`` names each sensor's class and options class; a new sensor is one module, its
options class and one line here (CONTRIBUTING.md shows the ideal sampler as the example).
"""

from simlunar.lidar.scan import SteeredBeamOptions
from simlunar.sensors.base import Acquisition, NothingMeasured, Sensor
from simlunar.sensors.ideal import IdealOptions, IdealSampler
from simlunar.sensors.lidar import (
    FlashLidar,
    FlashLidarOptions,
    LidarScene,
    SteeredBeam,
)
from simlunar.sensors.micromirror import MicromirrorFlash, MicromirrorOptions
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
    "steered_beam": (SteeredBeam, SteeredBeamOptions),
    "flash": (FlashLidar, FlashLidarOptions),
    "micromirror_flash": (MicromirrorFlash, MicromirrorOptions),
}

__all__ = [
    "MODES",
    "SENSORS",
    "Acquisition",
    "FlashLidar",
    "FlashLidarOptions",
    "IdealOptions",
    "IdealSampler",
    "LidarScene",
    "MicromirrorFlash",
    "MicromirrorOptions",
    "NothingMeasured",
    "ScanResult",
    "Sensor",
    "SteeredBeam",
    "SteeredBeamOptions",
    "StructuredLight",
    "StructuredLightOptions",
]
