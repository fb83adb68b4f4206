"""The one atomic-write mechanism behind EXR, PNG, DEM, scene and cache files."""

from __future__ import annotations

import os
import stat

import pytest

from simlunar import atomic


def test_write_lands_whole_with_ordinary_permissions_and_no_temporary(tmp_path):
    p = tmp_path / "a.exr"
    seen = []

    def write(tmp):
        seen.append(tmp)
        assert tmp.endswith(".exr")  # writers pick the format from the suffix
        with open(tmp, "w") as f:
            f.write("data")

    assert atomic.atomic_write(p, write) == p
    assert p.read_text() == "data" and os.listdir(tmp_path) == ["a.exr"]
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(p.stat().st_mode) == 0o666 & ~umask
    assert os.path.dirname(seen[0]) == str(tmp_path)  # same folder: rename is atomic


def test_a_failing_writer_leaves_the_old_file_and_no_temporary(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text("old")

    def write(tmp):
        with open(tmp, "w") as f:
            f.write("half")
        raise KeyboardInterrupt  # an interrupt mid-write

    with pytest.raises(KeyboardInterrupt):
        atomic.atomic_write(p, write)
    assert p.read_text() == "old" and os.listdir(tmp_path) == ["a.txt"]


def test_missing_folder_is_named_unless_parents_are_made(tmp_path):
    target = tmp_path / "no" / "such" / "f.bin"
    with pytest.raises(FileNotFoundError, match=r"folder for .*f\.bin does not exist"):
        atomic.atomic_write(target, lambda tmp: None)
    atomic.atomic_write_bytes(target, b"xyz")
    assert target.read_bytes() == b"xyz"
