"""Checks of where a run writes: a result folder that is (or can be made) writable, an output
file that can be written, before anything is written (split from
:mod:`simlunar.pipeline.preflight`, which re-exports both)."""

from __future__ import annotations

import os
from pathlib import Path

from simlunar.errors import ResultFolderError
from simlunar.results.store import LOCK_NAME

__all__ = ["check_out_dir", "check_out_file"]


def check_out_dir(out: str | Path, *, option: str = "--out") -> Path:
    """Raise :class:`ResultFolderError` unless ``out`` is (or can be made) a writable folder.

    Nothing is created. Checks: ``out`` is not a file; no ancestor is a file; the nearest
    existing ancestor is writable and not on a read-only filesystem; ``out/units`` and
    ``out/figures`` are folders where they exist.
    """
    p = Path(out)
    if p.exists() and not p.is_dir():
        raise ResultFolderError(f"{option} {p}: is a file, not a folder")
    anc = p
    while not anc.exists() and not anc.is_symlink():
        if anc.parent == anc:
            break
        anc = anc.parent
    if anc.exists() and not anc.is_dir():
        raise ResultFolderError(f"{option} {p}: {anc} is a file, so no folder can be made in it")
    if not anc.exists():
        raise ResultFolderError(f"{option} {p}: {anc} is a broken link")
    try:
        read_only = bool(os.statvfs(anc).f_flag & os.ST_RDONLY)
    except OSError:
        read_only = False
    if read_only:
        raise ResultFolderError(f"{option} {p}: {anc} is on a read-only filesystem")
    if not os.access(anc, os.W_OK | os.X_OK):
        raise ResultFolderError(f"{option} {p}: {anc} is not writable (permission denied)")
    if p.is_dir():
        for sub in ("units", "figures", "scans", "arrays", "config.yaml", LOCK_NAME):
            q = p / sub
            want_dir = sub not in ("config.yaml", LOCK_NAME)
            if q.exists() and q.is_dir() != want_dir:
                kind = "a folder" if want_dir else "a file"
                raise ResultFolderError(f"{option} {p}: {q} is not {kind}")
            if q.is_dir() and not os.access(q, os.W_OK | os.X_OK):
                raise ResultFolderError(f"{option} {p}: {q} is not writable (permission denied)")
    return p


def check_out_file(out: str | Path, *, option: str = "--out") -> Path:
    """Raise :class:`ResultFolderError` unless ``out`` can be written as a file: not a folder,
    in a folder that exists or can be made (:func:`check_out_dir` of its parent)."""
    p = Path(out)
    if p.is_dir():
        raise ResultFolderError(f"{option} {p}: is a folder, not a file")
    check_out_dir(p.parent, option=f"{option} {p}:")
    if p.exists() and not os.access(p, os.W_OK):
        raise ResultFolderError(f"{option} {p}: is not writable (permission denied)")
    return p
