"""Atomic file writes, shared by every package that writes results.

A file is written to a temporary name in its target folder, then renamed over the target
(``os.replace`` is atomic on POSIX), so an interrupt never leaves a half-written EXR, DEM or
cache entry: readers see the old file or the new one. On failure the temporary file is removed.
"""

from __future__ import annotations

import errno
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

__all__ = ["WRAPPED_ERRNOS", "atomic_write", "atomic_write_bytes", "environment_errno"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write(
    path: str | Path, write: Callable[[str], None], *, make_parents: bool = False
) -> Path:
    """Call ``write(tmp_path)`` to fill a temporary file, then move it to ``path``.

    The temporary file keeps ``path``'s suffix (writers such as OpenEXR or Pillow pick the
    format from it) and gets ordinary permissions (0666 minus the umask; ``mkstemp`` makes
    0600). Without ``make_parents`` a missing folder raises ``FileNotFoundError`` naming it.
    """
    path = Path(path)
    if make_parents:
        path.parent.mkdir(parents=True, exist_ok=True)
    elif not path.parent.exists():
        raise FileNotFoundError(f"folder for {path} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(
            prefix=f".{path.name}.", suffix=f".tmp{path.suffix}", dir=path.parent
        )
    except OSError as exc:  # name the file asked for, not the temporary one
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from exc
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.unlink(tmp)
        if isinstance(exc, OSError) and exc.filename in (None, tmp) and exc.errno is not None:
            # the OS reports a full disk from write()/fsync() without a file name: name
            # the file the user asked for (not the temporary one)
            raise OSError(exc.errno, exc.strerror or os.strerror(exc.errno), str(path)) from exc
        code = None if isinstance(exc, OSError) else environment_errno(exc, path.parent)
        if code is not None:
            # a writer that wraps the OS error in its own (OpenEXR: RuntimeError "... No
            # space left on device."): the environment failed, not the code
            raise OSError(code, os.strerror(code), str(path)) from exc
        raise
    return path


#: errno values a writing library may wrap in its own exception (message = strerror)
WRAPPED_ERRNOS = tuple(
    getattr(errno, n)
    for n in ("ENOSPC", "EDQUOT", "EROFS", "EIO", "EACCES", "EFBIG")
    if hasattr(errno, n)
)


def environment_errno(exc: BaseException, folder: Path) -> int | None:
    """The errno of an environment failure hidden in a non-OSError ``exc`` raised while
    writing into ``folder``: its message names the OS error (``strerror``), or the folder's
    filesystem has no space left. None when ``exc`` looks like anything else."""
    if not isinstance(exc, Exception):
        return None
    msg = str(exc).lower()
    for code in WRAPPED_ERRNOS:
        if os.strerror(code).lower() in msg:
            return code
    try:
        st = os.statvfs(folder)
    except OSError:
        return None
    if st.f_bfree == 0 or (st.f_bavail == 0 and os.geteuid() != 0):
        return errno.ENOSPC
    return None


def atomic_write_bytes(path: str | Path, data: bytes, *, make_parents: bool = True) -> Path:
    """Write ``data`` atomically and ``fsync`` it (cache entries must survive a power cut)."""

    def write(tmp: str) -> None:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())

    return atomic_write(path, write, make_parents=make_parents)
