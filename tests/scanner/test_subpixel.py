"""Sub-pixel stripe-edge refinement of a gray-code decode (simlunar/scanner/subpixel.py): hand
cases on one camera row, exact recovery of linear projector mappings, the compiled kernel against
the NumPy reference, and the input checks."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import gray_code as gc
from simlunar.scanner import subpixel
from tests.scanner.test_gray_code import _noisy_ramp_case, _ramp_stack

NAN = np.nan


def _one_row_decode(col, *, valid=None, lit=None):
    """A hand-made GrayDecode of one camera row over a 4-column, 2-row projector."""
    col = np.asarray(col, np.int64)[None]
    valid = np.ones(col.shape, bool) if valid is None else np.asarray(valid, bool)[None]
    lit = valid if lit is None else np.asarray(lit, bool)[None]
    zeros = np.zeros((3, *col.shape))
    return gc.GrayDecode(
        col=np.where(valid, col, -1),
        row=np.where(valid, 0, -1),
        valid=valid,
        lit=lit,
        bits=zeros.astype(np.uint8),
        reliable=zeros.astype(bool),
        n_col_bits=2,
        n_row_bits=1,
        proj_shape=(2, 4),
    )


# Camera pixel x (centre x + 0.5) sees projector u = (x + 0.5) / 2: columns 0,0,1,1,2,2,3,3 and
# stripe edges u = 1, 2, 3 at camera x = 2, 4, 6. Gray codes 00, 01, 11, 10: the edges 0|1 and
# 2|3 flip the LSB (diff plane 1), the edge 1|2 the MSB (plane 0). Each plane's signal is the
# signed projector distance to its nearest edge, positive where the bit is 1.
U = (np.arange(8) + 0.5) / 2
COLS = [0, 0, 1, 1, 2, 2, 3, 3]
MSB = U - 2.0
LSB = np.minimum(np.abs(U - 1), np.abs(U - 3)) * np.where((U > 1) & (U < 3), 1.0, -1.0)


def _diff(msb=MSB, lsb=LSB):
    row_plane = -np.ones(8)  # one projector row: no row edge anywhere
    return np.stack([msb, lsb, row_plane])[:, None, :]


def test_hand_case_one_row_interpolates_between_the_bracketing_edges():
    # edges at camera x = 2, 4, 6 with projector u = 1, 2, 3: pixels 2..5 lie between two edges
    # that bound their own stripe and get u = (x + 0.5) / 2; pixels 0, 1, 6, 7 have an edge on
    # one side only and stay NaN; rows cannot be refined (no row edge)
    dec = _one_row_decode(COLS)
    np.testing.assert_allclose(LSB, [-0.75, -0.25, 0.25, 0.75, 0.75, 0.25, -0.25, -0.75])
    sub = subpixel.refine_subpixel_from_diff(dec, _diff()).subpixel
    assert sub.shape == (1, 8, 2) and sub.dtype == np.float64
    np.testing.assert_allclose(sub[0, :, 0], [NAN, NAN, 1.25, 1.75, 2.25, 2.75, NAN, NAN])
    assert np.isnan(sub[..., 1]).all()


def test_hand_case_edge_is_the_linear_zero_crossing_between_pixel_centres():
    # guards the interpolation weight t = s0 / (s0 - s1): MSB signal -0.1 at x = 3, +0.3 at
    # x = 4 crosses zero at 3.5 + 0.25 = 3.75 (not at 4, the midpoint), so pixel 2 (centre 2.5)
    # between the edges at 2 (u = 1) and 3.75 (u = 2) gets 1 + 0.5 / 1.75, pixel 4 (centre 4.5)
    # between 3.75 (u = 2) and 6 (u = 3) gets 2 + 0.75 / 2.25
    msb = MSB.copy()
    msb[3], msb[4] = -0.1, 0.3
    sub = subpixel.refine_subpixel_from_diff(_one_row_decode(COLS), _diff(msb=msb)).subpixel
    np.testing.assert_allclose(
        sub[0, 2:6, 0], [1 + 0.5 / 1.75, 1 + 1.5 / 1.75, 2 + 0.75 / 2.25, 2 + 1.75 / 2.25]
    )


def test_hand_case_an_index_jump_of_two_is_no_edge():
    # a stripe decoded wrong (column 3 where 2 belongs, so 1 -> 3) is no stripe edge: the
    # pixels of column 1 lose their right edge and those decoded as 3 have no edge pair either
    cols = [0, 0, 1, 1, 3, 3, 3, 3]
    sub = subpixel.refine_subpixel_from_diff(_one_row_decode(cols), _diff()).subpixel
    assert np.isnan(sub[..., 0]).all()


def test_hand_case_unlit_pixel_between_two_valid_ones_hides_the_edge():
    # the gap may only cross lit pixels (a pixel straddling the edge); an unlit one (shadow)
    # means the two sides need not be neighbours on the surface
    valid = np.ones(8, bool)
    valid[3] = False  # pixel 3 unreliable ...
    lit_ok = np.ones(8, bool)
    crossed = subpixel.refine_subpixel_from_diff(
        _one_row_decode(COLS, valid=valid, lit=lit_ok), _diff(), max_gap=1
    ).subpixel
    # ... but lit: the MSB edge is found in its signal (zero crossing at x = 4), pixel 2 keeps u
    assert crossed[0, 2, 0] == pytest.approx(1.25)
    lit_no = lit_ok.copy()
    lit_no[3] = False
    shadow = subpixel.refine_subpixel_from_diff(
        _one_row_decode(COLS, valid=valid, lit=lit_no), _diff(), max_gap=1
    ).subpixel
    assert np.isnan(shadow[0, 2, 0])
    # and with max_gap = 0 no gap is crossed at all
    adjacent = subpixel.refine_subpixel_from_diff(
        _one_row_decode(COLS, valid=valid, lit=lit_ok), _diff(), max_gap=0
    ).subpixel
    assert np.isnan(adjacent[0, 2, 0])


def test_refine_subpixel_is_refine_from_diff_of_pattern_minus_inverse():
    # the stack form: images 0::2 are patterns, 1::2 inverses; pattern = (1 + d) / 2,
    # inverse = (1 - d) / 2 has pattern - inverse = d; the input decode is not modified
    dec = _one_row_decode(COLS)
    d = _diff()
    images = np.empty((6, 1, 8))
    images[0::2], images[1::2] = (1 + d) / 2, (1 - d) / 2
    out = subpixel.refine_subpixel(dec, images)
    np.testing.assert_array_equal(out.subpixel, subpixel.refine_subpixel_from_diff(dec, d).subpixel)
    assert dec.subpixel is None
    assert out.col is dec.col and out.valid is dec.valid
    # integer signals are taken as float64
    dint = np.round(4 * d).astype(np.int32)
    np.testing.assert_allclose(
        subpixel.refine_subpixel_from_diff(dec, dint).subpixel[0, 2:6, 0], [1.25, 1.75, 2.25, 2.75]
    )


def test_input_errors_name_the_expected_shapes():
    dec = _one_row_decode(COLS)
    with pytest.raises(
        ValueError,
        match=r"images must be the decoded \(6, 1, 8\) gray-code stack, "
        r"got shape \(4, 1, 8\)",
    ):
        subpixel.refine_subpixel(dec, np.zeros((4, 1, 8)))
    with pytest.raises(ValueError, match=r"got shape \(6, 8\)"):
        subpixel.refine_subpixel(dec, np.zeros((6, 8)))
    with pytest.raises(ValueError, match=r"diff must be \(3, 1, 8\), got \(2, 1, 8\)"):
        subpixel.refine_subpixel_from_diff(dec, np.zeros((2, 1, 8)))
    with pytest.raises(ValueError, match="max_gap must be >= 0 pixels, got -1"):
        subpixel.refine_subpixel_from_diff(dec, _diff(), max_gap=-1)


# --- linear projector mappings (moved from test_gray_code.py) ----------------------------------


def test_refine_subpixel_recovers_linear_projector_coordinates():
    # camera 2x finer than a 20 x 13 projector, tilted mapping with sub-pixel offsets
    W, H = 20, 13
    y, x = np.mgrid[0:24, 0:38] + 0.5
    u = 0.31 + 0.5 * x + 0.02 * y
    v = 0.17 + 0.5 * y - 0.01 * x
    images, white, black = _ramp_stack(u, v, W, H)
    dec = gc.decode(
        images, white, black, proj_shape=(H, W), black_threshold=0.5, white_threshold=0.0
    )
    assert np.array_equal(dec.col[dec.valid], np.floor(u).astype(int)[dec.valid])
    ref = subpixel.refine_subpixel(dec, images)
    sub = ref.subpixel
    refined = np.isfinite(sub).all(axis=-1) & dec.valid
    # every pixel bracketed by two edges in its row and column: all but the image borders
    assert refined[2:-2, 2:-2].all()
    np.testing.assert_allclose(sub[..., 0][refined], u[refined], atol=1e-9)
    np.testing.assert_allclose(sub[..., 1][refined], v[refined], atol=1e-9)
    # the integer decode is off by up to half a projector pixel; proj_uv uses the refinement
    assert np.abs(dec.proj_uv()[..., 0] - u)[refined].max() > 0.4
    np.testing.assert_allclose(ref.proj_uv()[refined], np.stack([u, v], -1)[refined], atol=1e-9)


def test_refine_subpixel_stays_inside_the_decoded_pixel_and_rejects_wrong_stack():
    W, H = 8, 4
    y, x = np.mgrid[0:6, 0:14] + 0.5
    u, v = 0.4 + 0.55 * x, 0.2 + 0.6 * y
    images, white, black = _ramp_stack(u, v, W, H)
    rng = np.random.default_rng(3)
    noisy = images + 0.05 * rng.standard_normal(images.shape)
    dec = gc.decode(
        noisy, white, black, proj_shape=(H, W), black_threshold=0.5, white_threshold=0.0
    )
    sub = subpixel.refine_subpixel(dec, noisy).subpixel
    ok = np.isfinite(sub[..., 0])
    assert ok.any()
    assert np.all(np.floor(sub[..., 0][ok]) == dec.col[ok])
    with pytest.raises(ValueError, match="gray-code stack"):
        subpixel.refine_subpixel(dec, noisy[:-2])


def test_refine_subpixel_finds_edges_across_unreliable_edge_pixels():
    # ramps 1 projector px wide each side: pattern - inverse = 2 * 0.5 * distance, so a pixel
    # within 0.15 projector px of any stripe edge fails a 0.15 reliability threshold
    W, H = 20, 13
    y, x = np.mgrid[0:24, 0:38] + 0.5
    u = 0.31 + 0.5 * x + 0.02 * y
    v = 0.17 + 0.5 * y - 0.01 * x
    images, white, black = _ramp_stack(u, v, W, H, slope=0.5)
    dec = gc.decode(
        images, white, black, proj_shape=(H, W), black_threshold=0.5, white_threshold=0.15
    )
    assert (dec.lit & ~dec.valid).sum() > 50  # lit but unreliable pixels at stripe edges
    adjacent = subpixel.refine_subpixel(dec, images, max_gap=0).subpixel
    across = subpixel.refine_subpixel(dec, images, max_gap=2).subpixel
    n_adj = np.isfinite(adjacent).all(-1).sum()
    ok = np.isfinite(across).all(-1)
    assert ok.sum() > n_adj + 50
    # the zero crossing is found in the unreliable pixel's signal: still exact on ramps
    np.testing.assert_allclose(across[ok], np.stack([u, v], -1)[ok], atol=1e-9)
    with pytest.raises(ValueError, match="max_gap must be >= 0"):
        subpixel.refine_subpixel(dec, images, max_gap=-1)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("max_gap", [0, 1, 2, 4])
def test_compiled_refinement_equals_the_numpy_reference(seed, max_gap):
    from reference_scanner import refine_along_rows_reference

    dec, images = _noisy_ramp_case(seed)
    assert (dec.lit & ~dec.valid).sum() > 20 and dec.valid.sum() > 200
    diff = images[0::2] - images[1::2]
    ncb = dec.n_col_bits
    ref_u = refine_along_rows_reference(dec.col, dec.valid, dec.lit, diff[:ncb], ncb, max_gap)
    ref_v = refine_along_rows_reference(
        dec.row.T,
        dec.valid.T,
        dec.lit.T,
        diff[ncb:].transpose(0, 2, 1),
        dec.n_row_bits,
        max_gap,
    ).T
    sub = subpixel.refine_subpixel(dec, images, max_gap=max_gap).subpixel
    np.testing.assert_array_equal(np.isfinite(sub[..., 0]), np.isfinite(ref_u))
    np.testing.assert_array_equal(np.isfinite(sub[..., 1]), np.isfinite(ref_v))
    np.testing.assert_allclose(sub[..., 0], ref_u, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sub[..., 1], ref_v, rtol=0, atol=1e-12)
    # float32 signals (what a streamed scan keeps) move the result by float32 rounding only
    sub32 = subpixel.refine_subpixel_from_diff(
        dec, diff.astype(np.float32), max_gap=max_gap
    ).subpixel
    both = np.isfinite(sub32) & np.isfinite(sub)
    assert both.sum() >= 0.99 * np.isfinite(sub).sum()
    np.testing.assert_allclose(sub32[both], sub[both], atol=1e-5)
