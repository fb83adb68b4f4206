"""The plain binary code through the gray code's decoder: its stack by hand, its coding from
the registry and YAML, the straddling pixel that makes it the gray code's counter-example,
its bit errors and sub-pixel edges scored with its own words."""

from __future__ import annotations

import dataclasses

import numpy as np

from simlunar.config.scanner import ScannerOptionsCfg
from simlunar.config.scanner_translate import coding_options
from simlunar.scanner import gray_code as gc
from simlunar.scanner import rigs
from simlunar.scanner.binary_code import BINARY, BinaryCodeOptions
from simlunar.scanner.bitcodes import GRAY, encode
from simlunar.scanner.codings import CODINGS, make_coding
from simlunar.scanner.gray_errors import bit_error_table
from simlunar.sensors.structured_light import MODES
from tests.scanner._synthetic import PlaneCapture


def test_binary_stack_by_hand_width4_height2():
    # columns 0..3 are 00, 01, 10, 11 (MSB first): image 0 the MSB, image 2 the LSB
    p = encode(4, 2, BINARY)
    np.testing.assert_array_equal(p[0, 0], [0, 0, 255, 255])
    np.testing.assert_array_equal(p[2, 1], [0, 255, 0, 255])
    np.testing.assert_array_equal(p[4][:, 0], [0, 255])
    np.testing.assert_array_equal(p[1::2], 255 - p[0::2])


def test_binary_is_a_coding_a_mode_and_a_yaml_block():
    assert "binary" in MODES and CODINGS["binary"].meta["yaml_key"] == "binary_opts"
    coding = make_coding("binary", {"subpixel": True})
    assert coding.options == BinaryCodeOptions(subpixel=True) and coding.options.code is BINARY
    assert coding.frames((96, 128)) == make_coding("gray_code").frames((96, 128))
    assert coding.export_meta(coding.decode(coding.patterns((4, 8)), (4, 8)))["code"] == "binary"
    opts = coding_options(ScannerOptionsCfg(binary_opts={"white_threshold": 0.02}))
    assert opts["binary"] == BinaryCodeOptions(white_threshold=0.02)
    assert opts["gray_code"].code is GRAY


def _straddling(code, n_bits=6, pixels=400, seed=0):
    """Decoded columns of camera pixels that each see half of column 2**(n-1) - 1 and half of
    the next (white 1, black 0, frame noise 0.01), every bit decided whatever its margin."""
    W = 1 << n_bits
    c = W // 2 - 1
    stack = encode(W, 2, code).astype(float) / 255  # (2 (n + 1), 2, W)
    mixed = 0.5 * (stack[:, 0, c] + stack[:, 0, c + 1])  # the pixel straddles the boundary
    rng = np.random.default_rng(seed)
    frames = mixed[:, None, None] + rng.normal(0, 0.01, (len(mixed), 1, pixels))
    dec = gc.decode(frames, np.ones((1, pixels)), np.zeros((1, pixels)), proj_shape=(2, W),
                    black_threshold=0.5, white_threshold=0.0, require_reliable=False, code=code)  # fmt: skip
    return dec.decoded_index()[0][0], c


def test_a_pixel_on_the_middle_boundary_is_off_by_half_the_projector_in_binary_not_in_gray():
    # all n binary bits flip between 31 and 32, one gray bit does (Salvi et al. 2004, 3.1)
    col, c = _straddling(GRAY)
    assert set(np.unique(col)) <= {c, c + 1}
    col, c = _straddling(BINARY)
    err = np.abs(col - c - 0.5)
    assert err.max() > 16 and np.mean(err > 1.5) > 0.5


def test_bit_errors_are_scored_with_the_binary_words():
    H, W = 4, 16
    coding = make_coding("binary")
    dec = coding.decode(coding.patterns((H, W)), (H, W))
    rr, cc = np.mgrid[0:H, 0:W]
    truth = {"col": cc, "row": rr, "lit": np.ones((H, W), bool)}
    assert all(v == 0 for v in bit_error_table(dec, truth, edge_margin=0).values())
    # one flipped column bit in one pixel: only that bit's rate moves, by one pixel in 64
    bits = dec.bits.copy()
    bits[3, 2, 5] ^= 1
    rates = bit_error_table(dataclasses.replace(dec, bits=bits), truth, edge_margin=0)
    assert rates["ber_c3"] == 1 / (H * W) and sum(rates.values()) == 1 / (H * W)


def test_binary_plane_scan_with_subpixel_edges_matches_the_gray_codes():
    rig = rigs.moonyard_rig(proj_size=(64, 48), cam_size=(128, 96))
    cap = PlaneCapture(rig, (0.2, -0.1, 1.0), 0.0, noise=0.002)
    kw = dict(black_threshold=0.2, white_threshold=0.05, subpixel=True)
    b = gc.gray_code_scan(cap, rig, BinaryCodeOptions(**kw))
    g = gc.gray_code_scan(cap, rig, gc.GrayCodeOptions(**kw))
    assert b.decode.code is BINARY and b.renders == g.renders == 6 + 6 + 2
    truth = cap.true_depth(rig.guide)
    ok = np.isfinite(b.depth) & np.isfinite(g.depth)
    assert ok.mean() > 0.85
    # the edges are found from the binary words (the highest flipping bit): refined pixels
    # exist, and the depth error is the gray code's within 20 %
    refined = np.isfinite(b.decode.subpixel[..., 0]) & b.decode.valid
    assert refined.mean() > 0.5
    rms_b = np.sqrt(np.mean((b.depth[ok] - truth[ok]) ** 2))
    rms_g = np.sqrt(np.mean((g.depth[ok] - truth[ok]) ** 2))
    assert rms_b < 1.2 * rms_g


def test_a_binary_scan_is_exported_under_its_own_name():
    # the gray and binary codes share their coding class: the export names a coding by its
    # options class too
    from simlunar.results.exports import _coding_name

    assert _coding_name(make_coding("binary")) == "binary"
    assert _coding_name(make_coding("gray_code")) == "gray_code"
