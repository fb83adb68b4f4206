"""The result folder: atomic writes and the per-unit cache.

Layout of ``<out>/``::

    config.yaml        the resolved experiment (defaults filled in, units as written)
    results.csv        tidy rows: unit, <sweep columns>, strategy, density, k, trial, metric, value
    scores.md          score tables (paper Tables 1 and 2 layout), Markdown
    scores.tex         the same tables, LaTeX (booktabs)
    provenance.json    versions, variant, git commit, seed, timings, cache hits, the
                       SHA-256 of config.yaml / results.csv / the tables and of every
                       input file (written last: its absence marks an unfinished run)
    units/<key>.json   one finished unit: rows, scores, timings (its existence marks completion)
    units/<key>.npz    the unit's arrays (image, depth, wavelet energy, plan, reconstruction)
    figures/           PNG and PDF
    .lock              held (``flock``) by the run writing into the folder

Every file is written to a temporary name in the same folder and moved into place with
``os.replace``, so a crash never leaves a half-written file under a final name. A unit's
``.npz`` is written before its ``.json``: a ``.json`` therefore always has its arrays.
"""

from __future__ import annotations

import csv
import errno
import fcntl
import io
import json
import os
import time
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from simlunar.atomic import atomic_write_bytes
from simlunar.errors import ResultFolderError

__all__ = [
    "LOCK_NAME",
    "UNITS_DIR",
    "FolderLock",
    "UnitCache",
    "atomic_write_bytes",
    "atomic_write_json",
    "atomic_write_text",
    "csv_text",
    "file_sha256",
    "fmt_value",
    "npz_bytes",
    "read_csv",
]

UNITS_DIR = "units"


def atomic_write_text(path: str | Path, text: str) -> None:
    atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_json(path: str | Path, obj: Any) -> None:
    atomic_write_text(path, json.dumps(obj, indent=2, sort_keys=True, allow_nan=True) + "\n")


def fmt_value(v: Any) -> str:
    """CSV text of a value: floats by ``repr`` (shortest round-trip), so files are exact."""
    if isinstance(v, (bool, np.bool_)):
        return str(bool(v)).lower()
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if v is None:
        return ""
    if isinstance(v, (list, tuple, dict)):
        return json.dumps(v, sort_keys=True)
    return str(v)


def csv_text(rows: list[dict], columns: list[str]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([fmt_value(r.get(c)) for c in columns])
    return buf.getvalue()


def read_csv(path: str | Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def npz_bytes(arrays: dict[str, np.ndarray], *, level: int = 1) -> bytes:
    """An ``.npz`` archive (what ``np.load`` reads) deflated at zlib ``level``.

    ``np.savez_compressed`` always uses zlib's default level 6; on float rasters level 1
    compresses almost as well (within a few per cent) in about a quarter of the time, and the
    cache write sits on the runner's critical path once per unit.
    """
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=level) as zf:
        for name, value in arrays.items():
            with zf.open(f"{name}.npy", "w", force_zip64=True) as f:
                np.lib.format.write_array(f, np.asarray(value), allow_pickle=False)
    return buf.getvalue()


class UnitCache:
    """Finished units of a result folder, keyed by the hash of their resolved config."""

    def __init__(self, out_dir: str | Path):
        self.dir = Path(out_dir) / UNITS_DIR

    def json_path(self, key: str) -> Path:
        return self.dir / f"{key}.json"

    def npz_path(self, key: str) -> Path:
        return self.dir / f"{key}.npz"

    def has(self, key: str) -> bool:
        return self.json_path(key).is_file()

    def load(self, key: str) -> dict | None:
        """The cached record of ``key``, or None when absent or unreadable (then recomputed)."""
        try:
            rec = json.loads(self.json_path(key).read_text())
        except (OSError, ValueError):
            return None
        if rec.get("key") != key:
            return None
        return rec

    def load_arrays(self, key: str, *, strict: bool = False) -> dict[str, np.ndarray]:
        """The unit's arrays; ``{}`` when unreadable, or with ``strict`` a
        :class:`~simlunar.errors.ResultFolderError` naming the file."""
        path = self.npz_path(key)
        try:
            # our own handle: np.load leaves a file it opened itself open when it is no zip
            with open(path, "rb") as f, np.load(f, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            if strict:
                raise ResultFolderError(
                    f"{path}: unreadable unit arrays ({' '.join(str(exc).split())}); "
                    "rerun the experiment into this folder to recompute the unit"
                ) from None
            return {}

    def arrays_readable(self, key: str) -> bool:
        """Whether the unit's ``.npz`` opens (its central directory reads); a truncated or
        garbage file fails here and the unit is recomputed."""
        try:
            with zipfile.ZipFile(self.npz_path(key)) as zf:
                return all(n.endswith(".npy") for n in zf.namelist())
        except (OSError, zipfile.BadZipFile, ValueError):
            return False

    def keys(self) -> set[str]:
        """Keys of every unit file (``.json`` or ``.npz``) in the folder."""
        if not self.dir.is_dir():
            return set()
        return {p.stem for p in self.dir.iterdir() if p.suffix in (".json", ".npz")}

    def remove_except(self, keep: set[str]) -> list[Path]:
        """Delete unit files whose key is not in ``keep`` and left-over temporary files."""
        removed = []
        if not self.dir.is_dir():
            return removed
        for p in sorted(self.dir.iterdir()):
            stale = p.suffix in (".json", ".npz") and p.stem not in keep
            temp = p.name.startswith(".") and ".tmp" in p.name
            if (stale or temp) and p.is_file():
                p.unlink()
                removed.append(p)
        return removed

    def save(self, key: str, record: dict, arrays: dict[str, np.ndarray]) -> None:
        atomic_write_bytes(self.npz_path(key), npz_bytes(arrays))
        atomic_write_json(self.json_path(key), {**record, "key": key})


_HASHES: dict[tuple, str] = {}


def file_sha256(path: str | Path) -> str:
    """SHA-256 (hex) of a file's bytes, remembered per (path, size, mtime, inode) in this
    process (a sweep hashes the same DEM once; an atomic rewrite is a new inode)."""
    import hashlib

    p = Path(path).resolve()
    st = p.stat()
    memo = (str(p), st.st_size, st.st_mtime_ns, st.st_ino)
    if memo not in _HASHES:
        h = hashlib.sha256()
        with open(p, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
        _HASHES[memo] = h.hexdigest()
    return _HASHES[memo]


LOCK_NAME = ".lock"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


class FolderLock:
    """An advisory lock that makes one run the owner of a result folder.

    ``<out>/.lock`` is locked with ``flock`` (the kernel releases it when the process exits,
    however it exits, so a lock of a killed run never blocks the next one) and holds the
    owner's pid, which a refused run names. A ``.lock`` file left by a dead process is not a
    lock: it is simply taken over. The file is removed when the lock is released.
    """

    def __init__(self, out_dir: str | Path):
        self.out = Path(out_dir)
        self.path = self.out / LOCK_NAME
        self.fd: int | None = None

    def acquire(self) -> FolderLock:
        """Take the lock or raise :class:`ResultFolderError` naming the owner's pid."""
        for _ in range(100):
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
            except IsADirectoryError:
                raise ResultFolderError(
                    f"{self.path}: is a folder, not the run's lock file (remove it)"
                ) from None
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                os.close(fd)
                if exc.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                    raise
                raise ResultFolderError(self._owner_message()) from None
            # the owner removes the file before unlocking: a file we locked after that is
            # no longer the folder's lock file, so lock the current one
            try:
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if not same:
                os.close(fd)
                continue
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()}\n".encode())
            self.fd = fd
            return self
        raise ResultFolderError(f"{self.path}: could not take the folder's lock")

    def _owner_message(self) -> str:
        pid = None
        for _ in range(20):  # the owner writes its pid just after locking
            try:
                text = self.path.read_text().strip()
            except OSError:
                text = ""
            if text.isdigit():
                pid = int(text)
                break
            time.sleep(0.025)
        who = f"pid {pid}" if pid is not None else "pid unknown"
        if pid is not None and not _pid_alive(pid):
            who += ", no longer running: a process it started still holds the lock"
        return (
            f"{self.out}: another simlunar run ({who}) is writing into this folder "
            f"(lock {self.path}); wait for it to finish or choose another --out"
        )

    def release(self) -> None:
        if self.fd is None:
            return
        try:
            os.unlink(self.path)
        except FileNotFoundError:
            pass
        os.close(self.fd)
        self.fd = None

    def __enter__(self) -> FolderLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()
