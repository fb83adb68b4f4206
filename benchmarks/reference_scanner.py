"""Reference (pre-streaming) implementations of the scan's per-frame steps, float64 NumPy.

Kept only as the ground truth that tests compare the compiled paths with and as the reference
path of the ``scanner_dlp`` benchmark; nothing in the library calls them.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from simlunar.scanner.dots import Detections
from simlunar.scanner.gray_code import GrayDecode, gray, gray_to_binary, num_bits


def apply_sensor_reference(radiance, model, *, rng=None) -> np.ndarray:
    """The float64 sensor model with NumPy's Poisson sampler (exact Poisson at every mean)."""
    gen = np.random.default_rng(rng)
    rad = np.nan_to_num(np.asarray(radiance, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    mean_e = np.clip(rad, 0.0, None) * model.exposure
    mean_e = np.minimum(mean_e, 16.0 * model.full_well_e + 1e6)
    e = np.minimum(gen.poisson(mean_e).astype(np.float64), model.full_well_e)
    if model.read_noise_e > 0:
        e += gen.normal(0.0, model.read_noise_e, size=e.shape)
    dn = np.clip(np.round(e / model.gain_e_per_dn) + model.black_level, 0, model.max_dn)
    v = dn / model.max_dn
    if model.response == "gamma":
        v = v ** (1.0 / model.gamma)
    return v.astype(np.float32)


def lens_reference(frames, sigma: float) -> np.ndarray:
    """Gaussian camera PSF on an (n, rows, cols) float64 stack (``ndimage.gaussian_filter``)."""
    frames = np.asarray(frames, np.float64)
    if sigma <= 0:
        return frames
    return ndimage.gaussian_filter(frames, (0, sigma, sigma), mode="nearest")


def edges_along_rows_reference(
    index: np.ndarray,
    valid: np.ndarray,
    lit: np.ndarray,
    diff: np.ndarray,
    n_bits: int,
    max_gap: int,
):
    """Stripe edges between horizontally consecutive valid camera pixels (refine_subpixel helper).

    ``index`` (rows, cols) decoded projector index, ``diff`` (n_bits, rows, cols) the
    pattern-minus-inverse signal of each gray bit. An edge follows valid pixel x when the next
    valid pixel x' in its row is at most ``max_gap + 1`` pixels on, every pixel between them is
    lit (they only failed the reliability test, as a pixel straddling a stripe edge does) and
    the two indices differ by exactly one: consecutive gray codes differ in one bit, whose
    signal changes sign across the edge. The first zero crossing of that signal from x to x',
    linear between pixel centres, is the edge's camera position.

    Returns
    -------
    ok : (rows, cols) bool, keyed by the left pixel x
    pos : (rows, cols) float64 camera coordinate of the edge (pixel centres at x + 0.5)
    u : (rows, cols) float64 projector coordinate of the edge (the boundary ``max(i, i')``)
    """
    rows, cols = index.shape
    r, c = np.indices((rows, cols))
    ok = np.zeros((rows, cols), bool)
    pos = np.full((rows, cols), np.nan)
    u = np.full((rows, cols), np.nan)
    between = np.ones((rows, cols), bool)  # every pixel from x + 1 to x + g - 1 is lit, invalid
    for g in range(1, max_gap + 2):
        if g >= cols:
            break
        a, b = index[:, :-g], index[:, g:]
        pair = valid[:, :-g] & valid[:, g:] & between[:, :-g] & ~ok[:, :-g]
        step = pair & (np.abs(a - b) == 1)
        lo = np.minimum(a, b)
        flip = gray(np.where(step, lo, 0)) ^ gray(np.where(step, lo + 1, 1))
        # bit position (MSB first) of the one gray bit that changes between lo and lo + 1
        k = np.clip(n_bits - 1 - np.log2(np.maximum(flip, 1)).astype(np.int64), 0, n_bits - 1)
        rr, cc = r[:, :-g], c[:, :-g]
        s_start = diff[k, rr, cc]
        found = np.zeros(step.shape, bool)
        where = np.full(step.shape, np.nan)
        for j in range(g):
            s0, s1 = diff[k, rr, cc + j], diff[k, rr, cc + j + 1]
            cross = step & ~found & (s0 * s_start > 0) & (s1 * s_start <= 0) & (s0 != s1)
            with np.errstate(divide="ignore", invalid="ignore"):
                t = np.clip(s0 / (s0 - s1), 0.0, 1.0)
            where = np.where(cross, cc + j + 0.5 + t, where)
            found |= cross
        ok[:, :-g] |= found
        pos[:, :-g] = np.where(found, where, pos[:, :-g])
        u[:, :-g] = np.where(found, lo + 1.0, u[:, :-g])
        # the next gap size needs pixel x + g to be lit and invalid, and x' = x + g + 1 valid
        between[:, :-g] &= lit[:, g:] & ~valid[:, g:]
    return ok, pos, u


def refine_along_rows_reference(index, valid, lit, diff, n_bits, max_gap) -> np.ndarray:
    """Sub-pixel projector index per camera pixel from the edges left and right of it."""
    ok, pos, u = edges_along_rows_reference(index, valid, lit, diff, n_bits, max_gap)
    rows, cols = index.shape
    e = np.arange(cols)
    # edges keyed by their left pixel: those keyed < x lie left of valid pixel x's centre,
    # those keyed >= x right of it
    left = np.maximum.accumulate(np.where(ok, e, -1), axis=1)
    right = np.minimum.accumulate(np.where(ok, e, cols)[:, ::-1], axis=1)[:, ::-1]
    li = np.full((rows, cols), -1)
    li[:, 1:] = left[:, :-1]
    ri = right
    has = (li >= 0) & (ri < cols) & valid
    r = np.indices((rows, cols))[0]
    lp = np.where(has, pos[r, np.clip(li, 0, cols - 1)], np.nan)
    rp = np.where(has, pos[r, np.clip(ri, 0, cols - 1)], np.nan)
    lu = np.where(has, u[r, np.clip(li, 0, cols - 1)], np.nan)
    ru = np.where(has, u[r, np.clip(ri, 0, cols - 1)], np.nan)
    # the pixel must lie in the one projector stripe bounded by the two edges
    has &= (np.abs(ru - lu) == 1) & (np.minimum(lu, ru) == index)
    xc = np.arange(cols) + 0.5
    with np.errstate(divide="ignore", invalid="ignore"):
        out = lu + (ru - lu) * (xc[None] - lp) / (rp - lp)
    out = np.clip(out, index, index + 1 - 1e-9)
    return np.where(has, out, np.nan)


def detect_dots_reference(
    image: np.ndarray,
    *,
    background=None,
    rel_threshold: float = 0.2,
    abs_threshold: float = 0.0,
    grow: int = 2,
    reject_border: bool = True,
) -> Detections:
    """Detect blobs and their intensity-weighted sub-pixel centroids.

    Pixels brighter than ``background + max(abs_threshold, rel_threshold * peak)`` (``peak`` = the
    brightest pixel above background) form 8-connected blobs; each blob's centroid is the
    intensity-weighted mean of pixel centres over the blob dilated by ``grow`` pixels, with
    weights ``max(image - background, 0)`` so the faint wings of a blurred spot count too.

    Parameters
    ----------
    image : (rows, cols) float
    background : float or (rows, cols) array, optional
        Image without the dots (e.g. the black frame); default the image median.
    rel_threshold, abs_threshold : float
    grow : int
    reject_border : bool
        Drop blobs whose grown region touches the image border (truncated spots).

    Returns
    -------
    Detections
    """
    img = np.asarray(image, float)
    if img.ndim != 2:
        raise ValueError(f"image must be 2-D (rows, cols), got {img.shape}")
    bg = np.median(img) if background is None else np.asarray(background, float)
    sig = np.maximum(img - bg, 0.0)
    peak = float(sig.max()) if sig.size else 0.0
    thr = max(abs_threshold, rel_threshold * peak)
    empty = Detections(np.empty((0, 2)), np.empty(0), np.empty(0))
    if peak <= 0 or peak <= abs_threshold:
        return empty
    labels, n = ndimage.label(sig > thr, structure=np.ones((3, 3), bool))
    if n == 0:
        return empty
    if grow > 0:
        # grow blobs without merging them: each pixel goes to the nearest label
        dist, (ir, ic) = ndimage.distance_transform_edt(labels == 0, return_indices=True)
        labels = np.where(dist <= grow, labels[ir, ic], 0)
    idx = np.arange(1, n + 1)
    rows, cols = np.mgrid[0 : img.shape[0], 0 : img.shape[1]]
    flux = ndimage.sum(sig, labels, idx)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = ndimage.sum(sig * (cols + 0.5), labels, idx) / flux
        v = ndimage.sum(sig * (rows + 0.5), labels, idx) / flux
    pk = ndimage.maximum(sig, labels, idx)
    ok = flux > 0
    if reject_border:
        # a spot cut by the image border has a biased centroid
        edge = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
        ok &= ~np.isin(idx, edge)
    return Detections(np.stack([u, v], axis=-1)[ok], np.asarray(flux)[ok], np.asarray(pk)[ok])


def decode_reference(
    images: np.ndarray,
    white: np.ndarray,
    black: np.ndarray,
    *,
    proj_shape: tuple[int, int],
    black_threshold: float = 40.0,
    white_threshold: float = 5.0,
    require_reliable: bool = True,
) -> GrayDecode:
    """Decode a gray-code image stack into per-pixel projector correspondences.

    Parameters
    ----------
    images : (2 * (num_bits(W) + num_bits(H)), rows, cols) array
        Captured (pattern, inverse) pairs in :func:`encode` order.
    white, black : (rows, cols) array
        Captured all-white and all-black frames.
    proj_shape : (H, W)
        Projector pattern shape (height, width).
    black_threshold, white_threshold : float
        OpenCV's thresholds, in the units of the images.
    require_reliable : bool
        If True (OpenCV's behaviour) a pixel with any unreliable bit is invalid.

    Returns
    -------
    GrayDecode
    """
    H, W = (int(proj_shape[0]), int(proj_shape[1]))
    ncb, nrb = num_bits(W), num_bits(H)
    images = np.asarray(images, dtype=np.float64)
    white = np.asarray(white, dtype=np.float64)
    black = np.asarray(black, dtype=np.float64)
    n_expected = 2 * (ncb + nrb)
    if images.ndim != 3 or images.shape[0] != n_expected:
        raise ValueError(
            f"images must be a ({n_expected}, rows, cols) gray-code stack for a {W}x{H} projector "
            f"({ncb} column + {nrb} row bits, pattern and inverse each), got shape {images.shape}"
        )
    if white.shape != images.shape[1:] or black.shape != images.shape[1:]:
        raise ValueError(
            f"white {white.shape} and black {black.shape} frames must match the "
            f"camera shape {images.shape[1:]}"
        )
    pat, inv = images[0::2], images[1::2]
    bits = (pat > inv).astype(np.uint8)
    reliable = np.abs(pat - inv) >= white_threshold
    lit = (white - black) > black_threshold
    col = gray_to_binary(bits[:ncb])
    row = gray_to_binary(bits[ncb:])
    valid = lit & (col < W) & (row < H)
    if require_reliable:
        valid &= np.all(reliable, axis=0)
    col = np.where(valid, col, -1)
    row = np.where(valid, row, -1)
    return GrayDecode(
        col=col,
        row=row,
        valid=valid,
        lit=lit,
        bits=bits,
        reliable=reliable,
        n_col_bits=ncb,
        n_row_bits=nrb,
        proj_shape=(H, W),
    )


def refine_subpixel_reference(result: GrayDecode, images, *, max_gap: int = 2) -> GrayDecode:
    """Sub-pixel refinement on a float64 stack with the NumPy edge search."""
    import dataclasses

    images = np.asarray(images, dtype=np.float64)
    diff = images[0::2] - images[1::2]
    ncb = result.n_col_bits
    u = refine_along_rows_reference(
        result.col, result.valid, result.lit, diff[:ncb], ncb, int(max_gap)
    )
    v = refine_along_rows_reference(
        result.row.T,
        result.valid.T,
        result.lit.T,
        diff[ncb:].transpose(0, 2, 1),
        result.n_row_bits,
        int(max_gap),
    ).T
    return dataclasses.replace(result, subpixel=np.stack([u, v], axis=-1))
