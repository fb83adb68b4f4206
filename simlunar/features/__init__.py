"""Image -> importance maps for image-directed range sampling (paper section 4.1).

``feature_map(name, image, **opts)`` returns a float64 (rows, cols) map >= 0; names are the
entries of :data:`MAPS` (:mod:`simlunar.features.registry`), each registered here once with
its options class: ``gradient``, ``entropy``, ``wavelet``, ``saliency`` and
``learned`` (a trained model, :mod:`simlunar.features.learned`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.features.log_energy import LogEnergyOptions, log_energy
from simlunar.features.maps import (
    EntropyOptions,
    WaveletOptions,
    check_image,
    entropy,
    gradient,
    to_gray,
    to_uint8,
    wavelet,
    wavelet_levels,
)
from simlunar.features.registry import MAPS, NoMapOptions, feature_map, image_maps, map_options
from simlunar.features.saliency import saliency
from simlunar.registry import FileOption, Options, option


# ---- maps that need a trained model, apart from the image-only maps ------------------------
@dataclass(frozen=True)
class LearnedMapOptions(Options):
    """Options of the learned map (:func:`simlunar.features.learned.learned`): the model file
    (from YAML) and the plan's density k / N (set by the planner, not a YAML key)."""

    model: str | None = option(
        None,
        doc="learned map: model file (.joblib beside its .json, written by `simlunar train`), "
        "relative to the working folder",
        # the record format of simlunar.features.learned (not imported here: scikit-learn)
        file=FileOption("model", "simlunar-learned-map/1"),
    )
    density: float | None = option(None, doc="learned map: the plan's k / N", gt=0, le=1)

    def __post_init__(self):
        super().__post_init__()
        if self.model is not None and not str(self.model).endswith(".joblib"):
            raise ValueError(f"a learned model file ends in .joblib, got {self.model!r}")


def _learned(image, *, model, density: float) -> np.ndarray:
    """``simlunar.features.learned.learned``, imported on use: that module imports
    scikit-learn and joblib, which every importer of this package (the planner, the studies,
    the runner) would otherwise load without a trained model to use them."""
    from simlunar.features.learned import learned

    return learned(image, model=model, density=density)


# The registry lives in .registry; its entries are added here. Meta: label (display name of
# the planner of the same name), combine (a map of the combination planner; the paper's four),
# cache_defaults (its options at their defaults are in the cache keys of runs made before this
# registry; a newer map's defaults are left out of them, so old caches stay valid).
_PAPER = {"combine": True, "cache_defaults": True}
MAPS.register("gradient", gradient, NoMapOptions, summary="gradient magnitude", label="Gradient",
              **_PAPER)  # fmt: skip
MAPS.register("entropy", entropy, EntropyOptions, summary="local entropy", label="Entropy",
              **_PAPER)  # fmt: skip
MAPS.register("wavelet", wavelet, WaveletOptions, summary="wavelet energy", label="Wavelet",
              **_PAPER)  # fmt: skip
MAPS.register("saliency", saliency, NoMapOptions, summary="Itti saliency", label="Saliency",
              **_PAPER)  # fmt: skip
MAPS.register("log_energy", log_energy, LogEnergyOptions, summary="LoG energy", label="LoG energy")
MAPS.register(
    "learned", _learned, LearnedMapOptions, summary="trained model", label="Learned",
    needs_model=True, runtime=("density",), cache_defaults=True,
)  # fmt: skip

#: name -> map function of the image-only maps (a view of :data:`MAPS`)
FEATURES = {n: MAPS[n].target for n in image_maps()}

__all__ = [
    "FEATURES",
    "MAPS",
    "EntropyOptions",
    "LearnedMapOptions",
    "NoMapOptions",
    "WaveletOptions",
    "check_image",
    "entropy",
    "feature_map",
    "gradient",
    "image_maps",
    "map_options",
    "saliency",
    "to_gray",
    "to_uint8",
    "wavelet",
    "wavelet_levels",
]
