"""Gray-code bit errors against the truth, with and without interreflections (paper section
5): helpers of the scanner study, re-exported by :mod:`simlunar.study.scanner`."""

from __future__ import annotations

import numpy as np

from simlunar.geometry import Rig
from simlunar.render.capture import CaptureOptions, RenderCapture, camera_truth, render_guide
from simlunar.scanner import gray_errors
from simlunar.scanner.gray_code import GrayCodeOptions, GrayScan, gray_code_scan

__all__ = ["bit_error_table", "interreflection_comparison"]


def bit_error_table(
    gray: GrayScan, truth: dict, mask=None, *, edge_margin: int = 1
) -> dict[str, float]:
    """Per-bit error rates of a gray-code decode against camera ground truth.

    ``mask`` (camera (rows, cols) bool) restricts the pixels; always only pixels lit by the
    projector in both the ground truth and the decode count, and for each bit only pixels
    ``edge_margin`` pixels away from that bit's true stripe edges
    (:func:`simlunar.scanner.gray_errors.stable_bits`; 0 keeps every pixel).
    """
    return gray_errors.bit_error_table(gray.decode, truth, mask, edge_margin=edge_margin)


def interreflection_comparison(
    terrain,
    rig: Rig,
    *,
    depths=(2, 3),
    mask_fn=None,
    spp: int = 16,
    seed: int = 0,
    bsdf=None,
    gray: GrayCodeOptions | None = None,
) -> dict:
    """Gray-code bit error rates with and without interreflections.

    Parameters
    ----------
    depths : path depths to compare (Mitsuba convention: 2 = direct only, >= 3 interreflections)
    mask_fn : callable(positions (rows, cols, 3)) -> bool (rows, cols), optional
        Selects camera pixels by the world point they see (e.g. inside craters).

    Returns
    -------
    dict depth -> dict of ``ber_c<i>`` / ``ber_r<i>`` rates (noise-free frames)
    """
    guide = render_guide(terrain, rig, spp=spp, seed=seed, bsdf=bsdf, max_depth=2)
    out = {}
    for depth in depths:
        cap = RenderCapture(
            terrain, rig, CaptureOptions(max_depth=depth, spp=spp, seed=seed), bsdf=bsdf
        )
        g = gray_code_scan(cap, rig, gray)
        truth = camera_truth(cap, guide)
        mask = None
        if mask_fn is not None:
            mask = np.asarray(mask_fn(np.asarray(cap.scene.ground_truth().position)), bool)
        out[depth] = bit_error_table(g, truth, mask)
    return out
