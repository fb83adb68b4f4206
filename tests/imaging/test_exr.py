import numpy as np
import pytest

from simlunar.imaging.exr import read_exr, write_exr


def test_named_channels_round_trip_bit_identical_with_attrs(tmp_path, rng):
    h = rng.normal(size=(7, 11)).astype(np.float32)
    h[2, 3] = np.nan  # nodata survives
    a = rng.random((7, 11)).astype(np.float32)
    attrs = {"spacing": 0.2, "origin": [1.5, -3.1], "note": "dem"}
    p = write_exr(tmp_path / "t.exr", {"height": h, "albedo": a}, attrs=attrs)
    chans, got = read_exr(p, with_attrs=True)
    assert set(chans) == {"height", "albedo"}
    assert chans["height"].dtype == np.float32
    np.testing.assert_array_equal(chans["height"], h)  # NaN == NaN in array_equal
    assert chans["albedo"].tobytes() == a.tobytes()
    # a plain float in the header would be float32; ours come back exactly
    assert got["spacing"] == 0.2 and got["origin"] == [1.5, -3.1] and got["note"] == "dem"
    assert not list(tmp_path.glob(".*tmp*"))  # the temporary file was renamed away


def test_array_inputs_map_to_y_and_rgb(tmp_path, rng):
    g = rng.random((4, 5)).astype(np.float32)
    assert set(read_exr(write_exr(tmp_path / "g.exr", g))) == {"Y"}
    rgb = rng.random((4, 5, 3)).astype(np.float32)
    ch = read_exr(write_exr(tmp_path / "c.exr", rgb))
    assert set(ch) == {"R", "G", "B"}
    np.testing.assert_array_equal(np.stack([ch["R"], ch["G"], ch["B"]], -1), rgb)


def test_float64_input_is_stored_as_float32(tmp_path):
    x = np.array([[0.1, 0.2], [0.3, 1e-9]])
    ch = read_exr(write_exr(tmp_path / "f.exr", {"Z": x}))
    np.testing.assert_array_equal(ch["Z"], x.astype(np.float32))


def test_errors_name_the_file_or_the_problem(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"missing\.exr"):
        read_exr(tmp_path / "missing.exr")
    bad = tmp_path / "corrupt.exr"
    bad.write_bytes(b"not an exr file" * 10)
    with pytest.raises(ValueError, match=r"corrupt\.exr"):
        read_exr(bad)
    with pytest.raises(ValueError, match="same shape"):
        write_exr(tmp_path / "x.exr", {"a": np.zeros((2, 2)), "b": np.zeros((2, 3))})
    with pytest.raises(ValueError, match="shape"):
        write_exr(tmp_path / "x.exr", np.zeros((2, 2, 5)))
    with pytest.raises(ValueError, match="JSON"):
        write_exr(tmp_path / "x.exr", np.zeros((2, 2)), attrs={"bad": object()})
    assert not (tmp_path / "x.exr").exists()
