"""Gray-code encode/decode: OpenCV layout, hand cases, round trips, decision rules."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import gray_code as gc
from simlunar.scanner import rigs
from simlunar.scanner.gray_code import GrayCodeOptions, gray_code_scan
from simlunar.sensors import StructuredLight, StructuredLightOptions
from tests.scanner._synthetic import PlaneCapture


def test_num_bits_matches_ceil_log2():
    assert [gc.num_bits(n) for n in (2, 3, 4, 5, 768, 1024, 1025)] == [1, 2, 2, 3, 10, 10, 11]
    with pytest.raises(ValueError, match="at least 2"):
        gc.num_bits(1)


def test_encode_hand_case_width4_height2():
    # columns 0..3 have gray codes 00, 01, 11, 10 (MSB first): OpenCV image 0 is the MSB
    # pattern, image 1 its inverse, image 2 the LSB; the single row bit follows.
    p = gc.encode(4, 2)
    assert p.shape == (2 * (2 + 1), 2, 4) and p.dtype == np.uint8
    np.testing.assert_array_equal(p[0, 0], [0, 0, 255, 255])
    np.testing.assert_array_equal(p[2, 1], [0, 255, 255, 0])
    np.testing.assert_array_equal(p[4][:, 0], [0, 255])
    np.testing.assert_array_equal(p[1::2], 255 - p[0::2])


def test_opencv_stack_size_for_1024x768():
    assert gc.encode(1024, 768).shape == (40, 768, 1024)
    assert gc.positive_patterns(1024, 768).shape == (20, 768, 1024)


def test_gray_to_binary_inverts_gray(rng):
    x = rng.integers(0, 2**12, size=500)
    np.testing.assert_array_equal(gc.gray_to_binary(gc.bit_planes(x, 12)), x)
    # adjacent integers differ in exactly one gray bit
    diff = gc.bit_planes(np.arange(1, 4096), 12) != gc.bit_planes(np.arange(4095), 12)
    assert np.all(diff.sum(axis=0) == 1)


@pytest.mark.parametrize("size", [(37, 23), (100, 61), (64, 48), (3, 2)])
def test_decode_encode_round_trip_non_power_of_two(size):
    W, H = size
    stack = gc.encode(W, H)
    white, black = gc.white_black(W, H)
    res = gc.decode(stack, white, black, proj_shape=(H, W))
    assert res.valid.all()
    rows, cols = np.mgrid[0:H, 0:W]
    np.testing.assert_array_equal(res.col, cols)
    np.testing.assert_array_equal(res.row, rows)


def test_decode_rules_shadow_unreliable_and_out_of_range():
    W, H = 5, 3  # 3 column bits: codes 5..7 are outside the projector
    stack = gc.encode(W, H).astype(float)
    white, black = (a.astype(float) for a in gc.white_black(W, H))
    black[0, 0] = 230.0  # white - black = 25 <= 40: shadow
    stack[2, 1, 1] = 128.0
    stack[3, 1, 1] = 125.0  # |pattern - inverse| = 3 < 5: unreliable bit
    res = gc.decode(stack, white, black, proj_shape=(H, W))
    assert not res.lit[0, 0] and not res.valid[0, 0] and res.col[0, 0] == -1
    assert res.lit[1, 1] and not res.reliable[1, 1, 1] and not res.valid[1, 1]
    relaxed = gc.decode(stack, white, black, proj_shape=(H, W), require_reliable=False)
    assert relaxed.valid[1, 1]
    # gray 100 (binary 7) is outside a 5-column projector
    col7 = gc.bit_planes(np.array([7]), 3)[:, 0] * 255.0
    stack[0:6:2, 2, 2] = col7
    stack[1:6:2, 2, 2] = 255 - col7
    assert not gc.decode(stack, white, black, proj_shape=(H, W)).valid[2, 2]


def test_decode_wrong_stack_shape_names_the_expected_shape():
    stack = gc.encode(16, 8)
    w, b = gc.white_black(16, 8)
    with pytest.raises(ValueError, match=r"\(14, rows, cols\) gray-code stack"):
        gc.decode(stack[:-2], w, b, proj_shape=(8, 16))
    with pytest.raises(ValueError, match="white"):
        gc.decode(stack, w[:, :3], b, proj_shape=(8, 16))


def test_inverses_by_linearity_equal_rendered_inverses(rng):
    # a linear light-transport matrix T (camera pixels x projector pixels) plus ambient light
    W, H, n_cam = 6, 4, 30
    T = rng.random((n_cam, W * H))
    ambient = rng.random(n_cam)
    pats = gc.encode(W, H).astype(float) / 255

    def image(p):
        return T @ p.reshape(-1) + ambient

    imgs = np.stack([image(p) for p in pats])
    white = image(np.ones((H, W)))
    black = image(np.zeros((H, W)))
    inv = gc.inverses_by_linearity(imgs[0::2, :, None], white[:, None], black[:, None])[..., 0]
    np.testing.assert_allclose(inv, imgs[1::2], rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="matching white/black"):
        gc.inverses_by_linearity(imgs[0::2, :, None], white[:5, None], black[:, None])


def _ramp_stack(u, v, W, H, slope=1.0):
    """Gray-code stack seen by a camera whose pixels see projector coordinates (u, v).

    Every pattern is a linear ramp of half-width 0.5 / slope projector px across each stripe
    edge (value 0.5 + slope * signed distance to the edge), so pattern - inverse is linear in u
    (or v) near an edge and its zero crossing sits at the edge.
    """
    ncb, nrb = gc.num_bits(W), gc.num_bits(H)

    def planes(coord, nbits):
        base = np.floor(coord).astype(np.int64)
        out = []
        for b in range(nbits):
            bit = gc.bit_planes(np.clip(base, 0, None), nbits)[b].astype(float)
            dist = np.full(coord.shape, 3.0)
            for off in range(-3, 5):
                n = base + off
                left = gc.bit_planes(np.clip(n - 1, 0, None), nbits)[b]
                right = gc.bit_planes(np.clip(n, 0, None), nbits)[b]
                flips = (left != right) & (n >= 1)
                dist = np.where(flips, np.minimum(dist, np.abs(coord - n)), dist)
            sign = np.where(bit > 0, 1.0, -1.0)
            out.append(np.clip(0.5 + slope * sign * dist, 0.0, 1.0))
        return out

    pats = planes(u, ncb) + planes(v, nrb)
    stack = []
    for p in pats:
        stack += [p, 1.0 - p]
    return np.stack(stack), np.ones_like(u), np.zeros_like(u)


# --- streaming decoder against decode -------------------------------------------------------


def _noisy_ramp_case(seed, slope=0.5, noise=0.03, white_threshold=0.1):
    W, H = 20, 13
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:26, 0:41] + 0.5
    # a wavy mapping with occlusion-like gaps: some pixels unlit, some decode wrong
    u = 0.31 + 0.47 * x + 0.03 * y + 0.4 * np.sin(x / 3.0)
    v = 0.17 + 0.49 * y - 0.01 * x + 0.3 * np.cos(y / 2.5)
    images, white, black = _ramp_stack(
        np.clip(u, 0, W - 1e-3), np.clip(v, 0, H - 1e-3), W, H, slope
    )
    images = images + noise * rng.standard_normal(images.shape)
    white = white.copy()
    white[rng.random(white.shape) < 0.05] = 0.0  # shadowed pixels
    dec = gc.decode(
        images,
        white,
        black,
        proj_shape=(H, W),
        black_threshold=0.5,
        white_threshold=white_threshold,
    )
    return dec, images


def test_streaming_decoder_equals_decode_in_any_order_and_reports_missing_frames():
    dec, images = _noisy_ramp_case(1)
    white = np.where(dec.lit, 1.0, 0.0)
    black = np.zeros_like(white)
    ref = gc.decode(
        images, white, black, proj_shape=(13, 20), black_threshold=0.5, white_threshold=0.1
    )
    s = gc.GrayDecoder(
        (13, 20), white.shape, black_threshold=0.5, white_threshold=0.1, keep_diff=True
    )
    nb = s.n_bits
    with pytest.raises(ValueError, match="missing frames: bit 0"):
        s.result()
    for k in np.random.default_rng(0).permutation(nb):
        s.add_pair(k, images[2 * k], images[2 * k + 1])
    with pytest.raises(ValueError, match="white/black"):
        s.result()
    s.add_white_black(white, black)
    out = s.result()
    for name in ("col", "row", "valid", "lit", "bits", "reliable"):
        np.testing.assert_array_equal(getattr(out, name), getattr(ref, name))
    np.testing.assert_array_equal(s.diff, images[0::2] - images[1::2])
    with pytest.raises(ValueError, match="bit must be"):
        s.add_pair(nb, images[0], images[1])
    with pytest.raises(ValueError, match="camera shape"):
        s.add_pair(0, images[0][:-1], images[1][:-1])


def test_default_white_threshold_is_opencvs_5():
    """OpenCV's rule with its default white threshold 5: a bit is unreliable where
    |pattern - inverse| < 5, so a difference of exactly 5 is reliable and 4 is not."""
    W, H = 5, 3
    stack = gc.encode(W, H).astype(float)
    white, black = (a.astype(float) for a in gc.white_black(W, H))
    stack[2, 1, 1], stack[3, 1, 1] = 130.0, 125.0
    stack[2, 2, 2], stack[3, 2, 2] = 129.0, 125.0
    res = gc.decode(stack, white, black, proj_shape=(H, W))
    assert res.reliable[1, 1, 1] and res.valid[1, 1]
    assert not res.reliable[1, 2, 2] and not res.valid[2, 2]


def test_proj_uv_is_the_decoded_pixel_centre_by_hand():
    """A camera that sees the projector pixel for pixel: camera pixel (r, c) decodes to column c
    and row r, so its projector coordinates are the pixel centre (c + 0.5, r + 0.5); a
    shadowed pixel has none (NaN)."""
    W, H = 6, 4
    stack = gc.encode(W, H).astype(float)
    white, black = (a.astype(float) for a in gc.white_black(W, H))
    black[3, 5] = 250.0  # white - black = 5 <= 40: shadow
    uv = gc.decode(stack, white, black, proj_shape=(H, W)).proj_uv()
    r, c = np.mgrid[0:H, 0:W]
    want = np.stack([c + 0.5, r + 0.5], axis=-1).astype(float)
    want[3, 5] = np.nan
    np.testing.assert_array_equal(uv, want)


def test_frame_names_by_hand():
    """OpenCV's order: each column bit's pattern then its inverse, MSB first, then the rows,
    then white and black."""
    assert gc.frame_names(2, 1) == [
        "col0", "col0_inv", "col1", "col1_inv", "row0", "row0_inv", "white", "black"
    ]  # fmt: skip
    names = gc.frame_names(gc.num_bits(1024), gc.num_bits(768))
    assert len(names) == 2 * (10 + 10) + 2 and names[-3] == "row9_inv"


def test_interleave_rebuilds_the_encoded_stack():
    """The positive patterns and their inverses interleaved are encode()'s stack; by hand
    on two 1 x 1 frames: [p0, i0, p1, i1]."""
    stack = gc.encode(6, 4)
    pos = gc.positive_patterns(6, 4)
    np.testing.assert_array_equal(gc.interleave(pos, 255 - pos), stack)
    out = gc.interleave(np.array([[[1.0]], [[2.0]]]), np.array([[[3.0]], [[4.0]]]))
    np.testing.assert_array_equal(out[:, 0, 0], [1.0, 3.0, 2.0, 4.0])


def test_decode_takes_frames_as_nested_lists():
    """Frames need only be array_like: the stack, white and black as nested lists decode as
    the arrays do (a camera that sees the projector pixel for pixel: column c, row r)."""
    W, H = 5, 3
    stack = gc.encode(W, H).astype(float)
    white, black = (a.astype(float) for a in gc.white_black(W, H))
    res = gc.decode(stack.tolist(), white.tolist(), black.tolist(), proj_shape=(H, W))
    r, c = np.mgrid[0:H, 0:W]
    assert res.valid.all()
    np.testing.assert_array_equal(res.col, c)
    np.testing.assert_array_equal(res.row, r)


@pytest.fixture
def rig():
    return rigs.moonyard_rig(proj_size=(64, 48), cam_size=(128, 96))


@pytest.mark.parametrize("normal", [(0, 0, 1.0), (0.3, -0.2, 1.0)])
def test_gray_code_scan_of_plane_matches_truth(rig, normal):
    cap = PlaneCapture(rig, normal, 0.0, noise=0.002)
    g = gray_code_scan(cap, rig, GrayCodeOptions(black_threshold=0.2, white_threshold=0.05))
    assert g.renders == 6 + 6 + 2 == cap.renders  # bits + 2 with inverses by linearity
    truth = cap.true_depth(rig.guide)
    ok = np.isfinite(g.depth)
    assert ok.mean() > 0.9
    # gray code quantises to whole projector columns: one column spans a depth interval of
    # about dz = z^2 / (f_p * b) along a ray (triangulation depth resolution); the decoded
    # point sits within half a column of the truth, so |error| <= dz / 2 plus the change of
    # depth across the guide pixel (half a pixel on the slope), here bounded by dz as well.
    dz = truth[ok] ** 2 / (rig.projector.intrinsics.fx * rig.baseline)
    err = np.abs(g.depth[ok] - truth[ok])
    assert np.all(err <= dz)
    assert np.median(err / dz) < 0.5
    ref = gray_code_scan(
        cap, rig, GrayCodeOptions(black_threshold=0.2, white_threshold=0.05, inverses="render")
    )
    assert ref.renders == 2 * 12 + 2
    np.testing.assert_array_equal(ref.decode.col, g.decode.col)


def test_gray_code_mode_measures_the_decoded_pixels(rig):
    cap = PlaneCapture(rig, (0, 0, 1.0), 0.0)
    gray = StructuredLightOptions(
        "gray_code", codings={"gray_code": GrayCodeOptions(black_threshold=0.2)}
    )
    sensor = StructuredLight(cap, rig, depth_range=(1.0, 3.0), options=gray)
    assert not sensor.needs_plan
    acq = sensor.acquire(None)
    res = acq.detail
    assert np.isnan(res.measured).any() and acq.frames == res.renders == 14
    # the acquisition holds exactly the finite cells of the measured map, row-major
    np.testing.assert_array_equal(acq.measured_map(), res.measured)
    assert len(acq.values) == np.isfinite(res.measured).sum()
