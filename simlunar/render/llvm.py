"""Discovery of a shared libLLVM that Dr.Jit's LLVM backend can use.

Dr.Jit 1.5 needs LLVM >= 16 (LLVM 14/15 abort inside the JIT with "Cannot select ... fminimum",
observed with Dr.Jit 1.5.0). This module never loads a library itself: it only lists candidates
and reads their versions from file names, so it is safe to import anywhere (no mitsuba/drjit).

Search order: ``DRJIT_LIBLLVM_PATH``, then a PyPI-packaged LLVM installed in the
current environment (``karellen-llvm-core``), then the system's libLLVM >= 16.

Run ``python -m simlunar.render.llvm`` to print the best candidate (exit 1 when none).
"""

from __future__ import annotations

import glob
import os
import re
import sys
import sysconfig
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "MIN_LLVM_MAJOR",
    "LLVMCandidate",
    "candidates",
    "find_libllvm",
    "llvm_major_from_name",
    "main",
]

MIN_LLVM_MAJOR = 16

_VERSION_RE = re.compile(r"libLLVM(?:-|\.so\.)(\d+)")


@dataclass(frozen=True)
class LLVMCandidate:
    """A shared libLLVM found on disk."""

    path: str
    major: int | None
    source: str  # "env", "pypi" or "system"

    @property
    def usable(self) -> bool:
        return self.major is None or self.major >= MIN_LLVM_MAJOR


def llvm_major_from_name(path: str) -> int | None:
    """Major version read off a library name (``libLLVM-19.so``, ``libLLVM.so.19.1``)."""
    m = _VERSION_RE.search(os.path.basename(path))
    return int(m.group(1)) if m else None


def _pypi_candidates() -> list[LLVMCandidate]:
    # karellen-llvm-core installs its library as wheel data: <prefix>/lib/libLLVM.so.23.1
    paths = set(glob.glob(os.path.join(sys.prefix, "lib", "libLLVM*.so*")))
    for root in {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}:
        paths |= set(glob.glob(os.path.join(root, "*llvm*", "**", "libLLVM*.so*"), recursive=True))
    found = []
    for p in sorted(paths):
        if os.path.isfile(p) and not os.path.islink(p):
            found.append(LLVMCandidate(p, llvm_major_from_name(p), "pypi"))
    return sorted(found, key=lambda c: -(c.major or 0))


def _system_candidates() -> list[LLVMCandidate]:
    patterns = [
        "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
        "/usr/lib/aarch64-linux-gnu/libLLVM*.so*",
        "/usr/lib/llvm-*/lib/libLLVM*.so*",
        "/usr/lib64/libLLVM*.so*",
        "/usr/local/lib/libLLVM*.so*",
        "/usr/lib/libLLVM*.so*",
    ]
    seen: dict[str, LLVMCandidate] = {}
    for pat in patterns:
        for p in glob.glob(pat):
            real = os.path.realpath(p)
            if real in seen or not os.path.isfile(real):
                continue
            major = llvm_major_from_name(p) or llvm_major_from_name(real)
            seen[real] = LLVMCandidate(p, major, "system")
    return sorted(seen.values(), key=lambda c: -(c.major or 0))


def candidates() -> list[LLVMCandidate]:
    """All libLLVM candidates in search order (best first within each source)."""
    out: list[LLVMCandidate] = []
    env = os.environ.get("DRJIT_LIBLLVM_PATH")
    if env:
        out.append(LLVMCandidate(env, llvm_major_from_name(env), "env"))
    out += _pypi_candidates()
    out += _system_candidates()
    return out


def find_libllvm() -> LLVMCandidate | None:
    """The first candidate that exists and is new enough, or ``None``."""
    for c in candidates():
        if Path(c.path).exists() and c.usable:
            return c
    return None


def main() -> int:
    best = find_libllvm()
    if best is None:
        olds = ", ".join(f"{c.path} (LLVM {c.major})" for c in candidates()) or "none"
        print(f"no usable libLLVM >= {MIN_LLVM_MAJOR} found; candidates: {olds}", file=sys.stderr)
        return 1
    print(best.path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
