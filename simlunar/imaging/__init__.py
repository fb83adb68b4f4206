"""Images in and out: sensor model (noise, ADC, response), OpenEXR and sRGB PNG I/O."""

from simlunar.imaging.exr import read_exr, write_exr
from simlunar.imaging.png import write_png_preview
from simlunar.imaging.sensor import SensorModel, apply_sensor

__all__ = ["SensorModel", "apply_sensor", "read_exr", "write_exr", "write_png_preview"]
