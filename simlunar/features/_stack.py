"""Per-pixel feature stack of a guide image for the learned importance map.

Only the image is read (never depth). Every feature is float32 and most are logarithms of
energies, so that a global exposure change of the image shifts them by a constant instead of
scaling them (the image is also divided by its mean first). The stack is versioned: a model
trained on one :data:`FEATURE_SET_VERSION` refuses images featurised by another.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pywt
from scipy import ndimage

from simlunar.features.maps import to_gray, wavelet_levels

__all__ = ["FEATURE_NAMES", "FEATURE_SET_VERSION", "image_features"]

#: bump whenever a feature's definition, order or count changes (saved models then refuse)
FEATURE_SET_VERSION = 1

#: wavelet detail levels kept (finest first); deeper levels of small images are zero
WAVELET_LEVELS = (1, 2, 3, 4, 5)
#: Gaussian scales (px) of the gradient and Laplacian-of-Gaussian energies
DERIV_SIGMAS = (1.0, 2.0, 4.0, 8.0)
#: Gaussian scales (px) at which the total wavelet energy is averaged
WAVELET_SIGMAS = (2.0, 4.0, 8.0, 16.0)
#: window sides (px) of the local mean and standard deviation
LOCAL_WINDOWS = (2, 8, 32)
#: a pixel is in shadow below this fraction of the image's 99th percentile
SHADOW_LEVEL = 0.05
#: window side (px) of the shadow fraction
SHADOW_WINDOW = 8
#: base features that are also averaged over half a pitch and one pitch
PITCH_SMOOTHED = ("wavelet", "grad_s1", "grad_s2", "log_s1", "log_s2", "std_w2", "shadow")
_EPS = 1e-8


def _base_names() -> list[str]:
    names = [f"wavelet_l{j}" for j in WAVELET_LEVELS]
    names += [f"wavelet_g{s:g}" for s in WAVELET_SIGMAS]
    names += [f"grad_s{s:g}" for s in DERIV_SIGMAS] + [f"log_s{s:g}" for s in DERIV_SIGMAS]
    names += [f"mean_w{w}" for w in LOCAL_WINDOWS] + [f"std_w{w}" for w in LOCAL_WINDOWS]
    return [*names, "intensity", "shadow", "border_px", "border_pitch", "wavelet"]


#: feature names in stack order (41 with the defaults)
FEATURE_NAMES: tuple[str, ...] = tuple(
    _base_names() + [f"{n}_p{f}" for f in ("half", "one") for n in PITCH_SMOOTHED]
)


def _log(x: np.ndarray) -> np.ndarray:
    return np.log(np.maximum(x, 0.0) + _EPS).astype(np.float32)


def _energies(g: np.ndarray) -> dict[str, np.ndarray]:
    """Linear (not yet logged) energies of the normalised gray image, by feature name."""
    out = {}
    # deepest level pywt decomposes without boundary warnings (the image is mirrored to 2x)
    usable = pywt.dwt_max_level(2 * min(g.shape), pywt.Wavelet("db2").dec_len)
    levels = wavelet_levels(g, levels=max(1, min(max(WAVELET_LEVELS), usable)))
    for j in WAVELET_LEVELS:
        out[f"wavelet_l{j}"] = levels[j - 1] if j <= len(levels) else np.zeros_like(g)
    total = np.sum(levels, axis=0)
    out["wavelet"] = total
    for s in WAVELET_SIGMAS:
        out[f"wavelet_g{s:g}"] = ndimage.gaussian_filter(total, s, mode="reflect")
    for s in DERIV_SIGMAS:
        gr = ndimage.gaussian_gradient_magnitude(g, s, mode="reflect")
        # scale-normalised (sigma^2 LoG) so the scales compare
        lg = s * s * ndimage.gaussian_laplace(g, s, mode="reflect")
        out[f"grad_s{s:g}"] = gr * gr
        out[f"log_s{s:g}"] = lg * lg
    return out


def _local(g: np.ndarray, gray: np.ndarray) -> dict[str, np.ndarray]:
    """Local statistics (already on their final scale) by feature name."""
    out = {}
    for w in LOCAL_WINDOWS:
        m = ndimage.uniform_filter(g, w, mode="reflect")
        m2 = ndimage.uniform_filter(g * g, w, mode="reflect")
        out[f"mean_w{w}"] = m
        out[f"std_w{w}"] = np.sqrt(np.maximum(m2 - m * m, 0.0))
    out["intensity"] = g
    top = float(np.percentile(gray, 99.0))
    dark = (gray <= SHADOW_LEVEL * top).astype(np.float64)
    out["shadow"] = ndimage.uniform_filter(dark, SHADOW_WINDOW, mode="reflect")
    return out


def _border(shape, pitch: float) -> dict[str, np.ndarray]:
    rows, cols = shape
    r = np.minimum(np.arange(rows), rows - 1 - np.arange(rows)).astype(np.float64)
    c = np.minimum(np.arange(cols), cols - 1 - np.arange(cols)).astype(np.float64)
    d = np.minimum(r[:, None], c[None, :])
    return {"border_px": np.log1p(d), "border_pitch": np.minimum(d / pitch, 4.0)}


def image_features(image, *, pitch: float) -> np.ndarray:
    """Per-pixel features of a guide image, :data:`FEATURE_NAMES` in order.

    Parameters
    ----------
    image : ndarray, shape (rows, cols) or (rows, cols, 3)
        Guide image (any positive intensity scale; divided by its mean first), finite.
    pitch : float
        Sample spacing in pixels, sqrt(N / k) = density^(-1/2); sets the two pitch-smoothed
        copies (Gaussian sigma pitch / 2 and pitch) and the border distance in pitches.

    Returns
    -------
    ndarray of float32, shape (rows, cols, len(FEATURE_NAMES))
        Log energies of wavelet levels 1-5 and of the total wavelet energy at 4 scales, of the
        gradient and scale-normalised LoG at sigma 1, 2, 4, 8 px; local mean and standard
        deviation at 2, 8, 32 px; intensity; shadow fraction; distance to the image border
        (log1p px, and in pitches capped at 4); the log total wavelet energy; then
        :data:`PITCH_SMOOTHED` averaged over half a pitch and one pitch.
    """
    if not pitch >= 1.0:
        raise ValueError(f"pitch must be >= 1 pixel, got {pitch}")
    gray = to_gray(image)
    mean = float(gray.mean())
    g = gray / mean if mean > 0 else gray
    lin = _energies(g)
    feats = {n: _log(v) for n, v in lin.items()}
    feats.update({n: v.astype(np.float32) for n, v in _local(g, gray).items()})
    feats.update({n: v.astype(np.float32) for n, v in _border(g.shape, pitch).items()})
    linear = {**lin, **_local(g, gray)}
    for tag, sigma in (("half", 0.5 * pitch), ("one", pitch)):
        for n in PITCH_SMOOTHED:
            sm = ndimage.gaussian_filter(linear[n], sigma, mode="reflect")
            feats[f"{n}_p{tag}"] = _log(sm) if n not in ("std_w2", "shadow") else sm
    out = np.empty((*g.shape, len(FEATURE_NAMES)), dtype=np.float32)
    for i, n in enumerate(FEATURE_NAMES):
        out[..., i] = feats[n]
    return out


# ---- the model files of the learned map and the learned reconstruction (both read this stack) ----
def _model_path(path) -> Path:
    path = Path(path)
    if path.suffix != ".joblib":
        raise ValueError(f"a learned model file ends in .joblib, got {str(path)!r}")
    return path


def _sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()
