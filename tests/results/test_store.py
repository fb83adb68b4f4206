"""Atomic writes and the unit cache."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest

from simlunar import atomic
from simlunar.results.store import UnitCache, atomic_write_text, csv_text, fmt_value


def test_atomic_write_replaces_and_leaves_no_temporary(tmp_path):
    p = tmp_path / "sub" / "a.txt"
    atomic_write_text(p, "one")
    atomic_write_text(p, "two")
    assert p.read_text() == "two"
    assert [q.name for q in p.parent.iterdir()] == ["a.txt"]
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(p.stat().st_mode) == 0o666 & ~mask


def test_a_failed_write_keeps_the_old_file(tmp_path, monkeypatch):
    p = tmp_path / "a.txt"
    atomic_write_text(p, "old")

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(atomic.os, "replace", boom)
    with pytest.raises(OSError, match="disk full"):
        atomic_write_text(p, "new")
    assert p.read_text() == "old"
    assert [q.name for q in tmp_path.iterdir()] == ["a.txt"]


def test_fmt_value_round_trips_floats():
    for v in (0.1, 1 / 3, 2.0**-11, 1e-300, 12345.678):
        assert float(fmt_value(v)) == v
    assert fmt_value(np.float32(0.5)) == "0.5"
    assert fmt_value(np.int64(3)) == "3"
    assert fmt_value(None) == ""
    assert fmt_value(True) == "true"
    assert fmt_value({"kind": "sun"}) == '{"kind": "sun"}'
    assert csv_text([{"a": 1, "b": "x,y"}], ["a", "b"]) == 'a,b\n1,"x,y"\n'


def test_unit_cache_round_trip_and_corrupt_entries(tmp_path):
    c = UnitCache(tmp_path)
    assert not c.has("k1") and c.load("k1") is None
    c.save("k1", {"rows": [{"v": 1.5}]}, {"image": np.arange(6, dtype=np.float32).reshape(2, 3)})
    assert c.load("k1") == {"rows": [{"v": 1.5}], "key": "k1"}
    np.testing.assert_array_equal(c.load_arrays("k1")["image"], np.arange(6).reshape(2, 3))
    c.json_path("k2").write_text("{truncated")
    assert c.load("k2") is None  # unreadable -> recomputed, never trusted
    c.json_path("k3").write_text('{"key": "other"}')
    assert c.load("k3") is None


def test_folder_lock_excludes_a_second_owner_and_leaves_no_file(tmp_path):
    from simlunar.errors import ResultFolderError
    from simlunar.results.store import FolderLock

    a = FolderLock(tmp_path).acquire()
    assert (tmp_path / ".lock").read_text().strip() == str(os.getpid())
    with pytest.raises(ResultFolderError, match=rf"another simlunar run \(pid {os.getpid()}\)"):
        FolderLock(tmp_path).acquire()
    a.release()
    assert not (tmp_path / ".lock").exists()
    with FolderLock(tmp_path):  # free again
        pass


def test_unit_cache_prunes_other_keys_and_temporaries_and_checks_arrays(tmp_path):
    c = UnitCache(tmp_path)
    for k in ("keep", "old"):
        c.save(k, {"rows": []}, {"a": np.zeros(2)})
    (c.dir / ".keep.json.x1.tmp.json").write_text("{")
    removed = c.remove_except({"keep"})
    assert sorted(p.name for p in removed) == [".keep.json.x1.tmp.json", "old.json", "old.npz"]
    assert c.keys() == {"keep"} and c.arrays_readable("keep")
    c.npz_path("keep").write_bytes(b"PK\x03\x04 truncated")
    assert not c.arrays_readable("keep")
    with pytest.raises(Exception, match=r"keep\.npz: unreadable unit arrays"):
        c.load_arrays("keep", strict=True)
    assert c.load_arrays("keep") == {}
