#!/usr/bin/env bash
# Make sure Dr.Jit's LLVM backend has a shared libLLVM >= 16 (LLVM 14/15 crash Dr.Jit 1.5).
# Debian's libllvm19 when we are root with apt-get, otherwise a PyPI-packaged LLVM 23
# (karellen-llvm-core) inside the virtual environment. Idempotent.
set -euo pipefail
VPY=${1:-.venv/bin/python}
if "$VPY" -m simlunar.render.llvm >/dev/null 2>&1; then
  echo "libLLVM: $("$VPY" -m simlunar.render.llvm)"
  exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
  echo "libLLVM >= 16 missing: installing Debian's libllvm19"
  if ! DEBIAN_FRONTEND=noninteractive apt-get install -y -q libllvm19 >/dev/null 2>&1; then
    apt-get update -q >/dev/null 2>&1 || true
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q libllvm19 >/dev/null 2>&1 || true
  fi
fi
if ! "$VPY" -m simlunar.render.llvm >/dev/null 2>&1; then
  echo "libLLVM >= 16 still missing: installing karellen-llvm-core from PyPI into $(dirname "$VPY")/.."
  "$VPY" -m pip install -q karellen-llvm-core || true
fi
if "$VPY" -m simlunar.render.llvm >/dev/null 2>&1; then
  echo "libLLVM: $("$VPY" -m simlunar.render.llvm)"
else
  echo "WARNING: no usable libLLVM >= 16; simlunar will render with the slow scalar_rgb variant" >&2
fi
