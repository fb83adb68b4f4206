"""Mitsuba variant selection, libLLVM discovery, kernel cache and plugin registration.

This is the single entry point to Mitsuba: every other module of ``simlunar.render`` calls
:func:`mitsuba` (or :func:`init`) before touching Mitsuba, so the variant is chosen once, the
environment Dr.Jit reads (``DRJIT_LIBLLVM_PATH``, ``DRJIT_CACHE_DIR``) is set before Dr.Jit is
imported, and our BSDF plugins are registered only after the variant is set.

Order of preference: ``cuda_ad_rgb`` when a CUDA GPU is usable, else ``llvm_ad_rgb``
when a libLLVM >= 16 is found and passes a probe, else ``scalar_rgb`` with a one-line warning.
Old LLVM (14/15) aborts the whole process inside Dr.Jit, so every candidate is first tried in a
child process; the verdict is cached in the kernel-cache folder keyed by library path, size,
modification time and the Dr.Jit version, so the probe costs ~1 s once per machine.

Set ``SIMLUNAR_VARIANT`` to force a variant (``scalar_rgb``, ``llvm_ad_rgb``, ``cuda_ad_rgb``).
"""

from __future__ import annotations

import ctypes.util
import json
import os
import subprocess
import sys
import warnings
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

from simlunar.interrupts import deferred, interrupted
from simlunar.render import llvm as _llvm
from simlunar.render.plugins import plugin_modules

__all__ = [
    "JIT_VARIANTS",
    "KNOWN_VARIANTS",
    "SCALAR_VARIANT",
    "BackendInfo",
    "ScalarFallbackWarning",
    "choose_variant",
    "default_cache_dir",
    "info",
    "init",
    "is_initialised",
    "mitsuba",
    "register_plugin_hook",
    "set_render_threads",
    "versions",
]

JIT_VARIANTS = ("cuda_ad_rgb", "llvm_ad_rgb")
SCALAR_VARIANT = "scalar_rgb"
KNOWN_VARIANTS = (*JIT_VARIANTS, SCALAR_VARIANT)


class ScalarFallbackWarning(UserWarning):
    """Rendering falls back to the slow scalar variant."""


@dataclass
class BackendInfo:
    """What :func:`init` chose and why."""

    variant: str
    reason: str
    libllvm: str | None = None
    cache_dir: str | None = None
    probes: dict[str, str] = field(default_factory=dict)

    @property
    def is_jit(self) -> bool:
        return self.variant in JIT_VARIANTS

    def as_dict(self) -> dict[str, Any]:
        return {
            "variant": self.variant,
            "reason": self.reason,
            "libllvm": self.libllvm,
            "cache_dir": self.cache_dir,
            "probes": dict(self.probes),
        }


_INFO: BackendInfo | None = None
_MI: Any = None
_PLUGIN_HOOKS: list = []


def default_cache_dir() -> Path:
    """Project-local ignored kernel cache (``build/drjit-cache``) or a user cache folder."""
    env = os.environ.get("DRJIT_CACHE_DIR")
    if env:
        return Path(env)
    repo = Path(__file__).resolve().parents[2]
    if (repo / "pyproject.toml").exists() and os.access(repo, os.W_OK):
        return repo / "build" / "drjit-cache"
    return Path.home() / ".cache" / "simlunar" / "drjit"


_PROBE = r"""
import sys
import mitsuba as mi
variant = sys.argv[1]
if variant not in mi.variants():
    print("variant not compiled into this mitsuba"); sys.exit(3)
mi.set_variant(variant)
import drjit as dr
x = dr.arange(mi.Float, 64)
y = dr.minimum(dr.sqrt(x), x * 0.5) + dr.maximum(x, 1.0)
dr.eval(y)
s = mi.load_dict({"type": "scene", "s": {"type": "rectangle"},
                  "e": {"type": "constant"}, "integrator": {"type": "direct"},
                  "sensor": {"type": "perspective", "film": {"type": "hdrfilm", "width": 4, "height": 4}}})
img = mi.render(s, spp=1)
assert float(dr.sum(mi.TensorXf(img)).array[0]) > 0
print("ok")
"""


def _probe_key(variant: str, lib: str | None) -> str:
    parts = [variant, _drjit_version()]
    if lib:
        try:
            st = os.stat(lib)
            parts += [os.path.realpath(lib), str(st.st_size), str(int(st.st_mtime))]
        except OSError:
            parts.append(lib)
    return "|".join(parts)


def _drjit_version() -> str:
    try:
        return metadata.version("drjit")
    except metadata.PackageNotFoundError:
        return "?"


def _probe(
    variant: str, lib: str | None, cache_dir: Path, timeout: float = 180.0
) -> tuple[bool, str]:
    """Try ``variant`` in a child process (an old LLVM aborts the process, not us)."""
    cache_file = cache_dir / "simlunar-probes.json"
    key = _probe_key(variant, lib)
    try:
        cache = json.loads(cache_file.read_text())
    except (OSError, ValueError):
        cache = {}
    if key in cache:
        ok, msg = cache[key]
        return bool(ok), str(msg)
    env = dict(os.environ)
    env["DRJIT_CACHE_DIR"] = str(cache_dir)
    if lib:
        env["DRJIT_LIBLLVM_PATH"] = lib
    try:
        res = subprocess.run(
            [sys.executable, "-c", _PROBE, variant],
            env=env,
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )
        ok = res.returncode == 0 and res.stdout.strip().endswith("ok")
        tail = (res.stdout + res.stderr).strip().splitlines()
        if interrupted() or res.returncode in (-2, 130) or "KeyboardInterrupt" in res.stderr:
            # a Ctrl-C reached the probe (same process group): no verdict on the library
            raise KeyboardInterrupt
        msg = "ok" if ok else f"exit {res.returncode}: {tail[-1] if tail else 'no output'}"
    except subprocess.TimeoutExpired:
        # not cached: a slow start on a loaded machine says nothing about the library
        return False, f"probe timed out after {timeout:.0f} s"
    cache[key] = [ok, msg]
    try:
        cache_dir.mkdir(parents=True, exist_ok=True)
        tmp = cache_file.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(cache, indent=1))
        os.replace(tmp, cache_file)
    except OSError:
        pass
    return ok, msg


def _cuda_present() -> bool:
    return Path("/dev/nvidia0").exists() or ctypes.util.find_library("cuda") is not None


def choose_variant(prefer: str | None = None, cache_dir: Path | None = None) -> BackendInfo:
    """Decide the variant without importing Mitsuba in this process."""
    cache_dir = Path(cache_dir or default_cache_dir())
    prefer = prefer or os.environ.get("SIMLUNAR_VARIANT") or None
    if prefer is not None and prefer not in KNOWN_VARIANTS:
        raise ValueError(f"unknown variant {prefer!r}; valid: {', '.join(KNOWN_VARIANTS)}")
    probes: dict[str, str] = {}
    if prefer == SCALAR_VARIANT:
        return BackendInfo(
            SCALAR_VARIANT, "forced by SIMLUNAR_VARIANT/prefer", cache_dir=str(cache_dir)
        )

    if prefer in (None, "cuda_ad_rgb"):
        if _cuda_present():
            ok, msg = _probe("cuda_ad_rgb", None, cache_dir)
            probes["cuda_ad_rgb"] = msg
            if ok:
                return BackendInfo("cuda_ad_rgb", "CUDA GPU usable", None, str(cache_dir), probes)
        else:
            probes["cuda_ad_rgb"] = "no CUDA driver found"
        if prefer == "cuda_ad_rgb":
            raise RuntimeError(f"cuda_ad_rgb requested but unusable: {probes['cuda_ad_rgb']}")

    tried = []
    for cand in _llvm.candidates():
        if not Path(cand.path).exists():
            tried.append(f"{cand.path}: missing")
            continue
        if not cand.usable:
            tried.append(f"{cand.path}: LLVM {cand.major} < {_llvm.MIN_LLVM_MAJOR}")
            continue
        ok, msg = _probe("llvm_ad_rgb", cand.path, cache_dir)
        tried.append(f"{cand.path}: {msg}")
        if ok:
            probes["llvm_ad_rgb"] = "; ".join(tried)
            why = f"libLLVM {cand.major or '?'} from {cand.source} ({cand.path})"
            return BackendInfo("llvm_ad_rgb", why, cand.path, str(cache_dir), probes)
    probes["llvm_ad_rgb"] = "; ".join(tried) or "no libLLVM found"
    if prefer == "llvm_ad_rgb":
        raise RuntimeError(f"llvm_ad_rgb requested but unusable: {probes['llvm_ad_rgb']}")
    return BackendInfo(
        SCALAR_VARIANT,
        "no usable JIT backend: " + probes["llvm_ad_rgb"],
        None,
        str(cache_dir),
        probes,
    )


def register_plugin_hook(fn) -> None:
    """Call ``fn(mi)`` once the variant is set (BSDF registration); at once if already set."""
    _PLUGIN_HOOKS.append(fn)
    if _MI is not None:
        fn(_MI)


def init(prefer: str | None = None) -> BackendInfo:
    """Choose the variant, set Dr.Jit's environment, import Mitsuba and register plugins.

    Idempotent: later calls return the first choice (a different ``prefer`` raises).
    """
    global _INFO, _MI
    if _INFO is not None:
        if prefer is not None and prefer != _INFO.variant:
            raise RuntimeError(
                f"Mitsuba already initialised with {_INFO.variant}; cannot switch to {prefer} "
                "in the same process"
            )
        return _INFO
    info = choose_variant(prefer)
    cache_dir = Path(info.cache_dir or default_cache_dir())
    cache_dir.mkdir(parents=True, exist_ok=True)
    os.environ["DRJIT_CACHE_DIR"] = str(cache_dir)
    if info.libllvm:
        os.environ["DRJIT_LIBLLVM_PATH"] = info.libllvm
    # a Ctrl-C inside Mitsuba's and Dr.Jit's import and initialisation leaves them half set
    # up (NameError: _drjit_ext, aborts, the interrupt swallowed): it is raised after them
    with deferred():
        import mitsuba as mi

        mi.set_variant(info.variant)
        _register_plugins(mi)
    _INFO, _MI = info, mi
    if not info.is_jit:
        warnings.warn(
            "simlunar: rendering with the slow scalar_rgb variant "
            f"({info.reason}); install libLLVM >= 16 (`apt-get install libllvm19` or "
            "`pip install karellen-llvm-core`) or set DRJIT_LIBLLVM_PATH, then rerun `make setup`",
            ScalarFallbackWarning,
            stacklevel=2,
        )
    return info


def _register_plugins(mi) -> None:
    # the variant is set: now plugins that subclass mi.BSDF may be defined and registered
    for module in plugin_modules().values():
        module.register(mi)
    for hook in _PLUGIN_HOOKS:
        hook(mi)


def set_render_threads(n: int | None) -> int:
    """Limit Dr.Jit's CPU thread pool to ``n`` threads (``None``: one per core).

    Returns the previous thread count.
    """
    import drjit as dr

    old = int(dr.thread_count())
    dr.set_thread_count(int(n) if n else (os.cpu_count() or 1))
    return old


def mitsuba():
    """The Mitsuba module with the variant set (initialising on first use)."""
    if _MI is None:
        init()
    return _MI


def is_initialised() -> bool:
    """Whether :func:`init` has run in this process (Mitsuba imported, variant set)."""
    return _MI is not None


def info() -> BackendInfo:
    """The current backend choice (initialising on first use)."""
    if _INFO is None:
        init()
    assert _INFO is not None
    return _INFO


def versions() -> dict[str, str]:
    """Versions of the packages that shape results (for provenance and ``doctor``)."""
    out = {"python": sys.version.split()[0]}
    for pkg in (
        "simlunar",
        "mitsuba",
        "drjit",
        "numpy",
        "scipy",
        "PyWavelets",
        "OpenEXR",
        "colour-science",
        "trimesh",
        "pydantic",
    ):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out
