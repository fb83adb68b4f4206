"""Size limits of a run and header-only grid shapes (simlunar.pipeline.limits)."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest

from simlunar.errors import ConfigError
from simlunar.pipeline import inputs
from simlunar.pipeline.limits import (
    LIMIT_SETTINGS,
    MAX_CELLS,
    check_size,
    grid_file_shape,
    size_limit,
)


def test_default_and_override(monkeypatch):
    monkeypatch.delenv("SIMLUNAR_MAX_CELLS", raising=False)
    assert size_limit("SIMLUNAR_MAX_CELLS") == MAX_CELLS == LIMIT_SETTINGS["SIMLUNAR_MAX_CELLS"]
    monkeypatch.setenv("SIMLUNAR_MAX_CELLS", " 1e9 ")
    assert size_limit("SIMLUNAR_MAX_CELLS") == 1_000_000_000


@pytest.mark.parametrize("raw", ["lots", "0", "-5", "nan", "inf"])
def test_bad_setting_is_refused(monkeypatch, raw):
    monkeypatch.setenv("SIMLUNAR_MAX_UNITS", raw)
    with pytest.raises(ConfigError, match=f"SIMLUNAR_MAX_UNITS={raw}: expected a positive count"):
        size_limit("SIMLUNAR_MAX_UNITS")


def test_check_size_at_and_over_the_limit(monkeypatch):
    monkeypatch.setenv("SIMLUNAR_MAX_CELLS", "100")
    check_size("k", "a grid", 100)  # at the limit: allowed
    with pytest.raises(ConfigError, match=r"k: a grid = 101, more than the limit of 100 \(set"):
        check_size("k", "a grid", 101)


def test_npy_shape_from_the_header(tmp_path, monkeypatch):
    monkeypatch.delenv("SIMLUNAR_MAX_CELLS", raising=False)
    p = tmp_path / "dem.npy"
    np.save(p, np.zeros((3, 7), np.float32))
    assert grid_file_shape(p, "terrain.file") == (3, 7)
    monkeypatch.setenv("SIMLUNAR_MAX_CELLS", "20")
    with pytest.raises(ConfigError, match=r"terrain\.file: .*a 3 x 7 array = 21"):
        grid_file_shape(p, "terrain.file")


def test_truncated_npy_is_refused(tmp_path):
    p = tmp_path / "dem.npy"
    np.save(p, np.zeros((4, 5), np.float64))
    p.write_bytes(p.read_bytes()[:-8])  # one float64 short
    with pytest.raises(
        ConfigError, match=r"promises a 4 x 5 array \(160 bytes\) but the file holds 152"
    ):
        grid_file_shape(p, "k")


def test_npz_heights_and_unknown_suffix(tmp_path):
    p = tmp_path / "dem.npz"
    np.savez(p, heights=np.zeros((2, 6)))
    assert grid_file_shape(p, "k") == (2, 6)
    q = tmp_path / "other.npz"
    np.savez(q, z=np.zeros(3))
    assert zipfile.is_zipfile(q) and grid_file_shape(q, "k") is None
    assert grid_file_shape(tmp_path / "x.csv", "k") is None


def test_inputs_re_exports_the_limits():
    assert inputs.check_size is check_size and inputs.MAX_CELLS == MAX_CELLS
