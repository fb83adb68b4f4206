"""Tests of simlunar.results.ply: the header by hand, a byte round trip, error paths."""

import numpy as np
import pytest

from simlunar.results.ply import ply_records, write_ply

FIELDS = (("x", "<f8", "double"), ("n", "<i4", "int"), ("r", "u1", "uchar"))


def test_header_and_records_round_trip(tmp_path):
    rec = ply_records(2, FIELDS)
    rec["x"], rec["n"], rec["r"] = [1.5, -2.0], [3, -4], [0, 255]
    path = write_ply(tmp_path / "a.ply", rec, fields=FIELDS, comment="hello world")
    blob = path.read_bytes()
    header = (
        b"ply\nformat binary_little_endian 1.0\ncomment hello world\nelement vertex 2\n"
        b"property double x\nproperty int n\nproperty uchar r\nend_header\n"
    )
    assert blob.startswith(header)
    body = blob[len(header) :]
    assert len(body) == 2 * (8 + 4 + 1)  # packed little-endian records, no padding
    back = np.frombuffer(body, dtype=rec.dtype)
    np.testing.assert_array_equal(back, rec)
    assert np.frombuffer(body[:8], "<f8")[0] == 1.5


def test_empty_cloud_is_a_valid_file(tmp_path):
    path = write_ply(tmp_path / "e.ply", ply_records(0, FIELDS), fields=FIELDS, comment="c")
    assert path.read_bytes().endswith(
        b"element vertex 0\n" + b"property double x\nproperty int n\nproperty uchar r\nend_header\n"
    )


def test_errors(tmp_path):
    rec = ply_records(1, FIELDS)
    with pytest.raises(ValueError, match="one line"):
        write_ply(tmp_path / "b.ply", rec, fields=FIELDS, comment="a\nb")
    with pytest.raises(ValueError, match="records have fields"):
        write_ply(tmp_path / "b.ply", rec, fields=FIELDS[:2], comment="c")
    assert not (tmp_path / "b.ply").exists()
