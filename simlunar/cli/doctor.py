"""``simlunar doctor``: the renderer this machine would use, and why."""

from __future__ import annotations

import os
import platform

from simlunar.cli.common import echo, flag

__all__ = ["doctor"]

# The library is imported inside each command, not at the top: importing it takes about 3 s (the
# scientific stack, and config.registry, which reads every planner, sensor and renderer), which
# `simlunar doctor --help` and a mistyped option should not pay (0.3 s with these imports here).


def doctor(short: bool = flag("--short", "One line only.")) -> None:
    """Versions, the chosen Mitsuba variant and why, libLLVM, kernel cache, cores, GPU."""
    from simlunar.pipeline.preflight import check_renderer
    from simlunar.render import backend

    check_renderer()  # a bad SIMLUNAR_VARIANT in one line
    info = backend.choose_variant()
    if short:
        echo(f"simlunar doctor: variant {info.variant} ({info.reason})")
        return
    vers = backend.versions()
    echo("simlunar doctor")
    for k, v in vers.items():
        echo(f"  {k:<15} {v}")
    echo(f"  {'variant':<15} {info.variant}")
    echo(f"  {'why':<15} {info.reason}")
    for k, v in info.probes.items():
        echo(f"  {'probe ' + k:<15} {v}")
    echo(f"  {'libLLVM':<15} {info.libllvm or 'none'}")
    echo(f"  {'kernel cache':<15} {info.cache_dir}")
    echo(f"  {'cores':<15} {os.cpu_count()}")
    echo(f"  {'machine':<15} {platform.machine()} {platform.system()}")
    gpu = "CUDA device present" if backend._cuda_present() else "none"
    echo(f"  {'GPU':<15} {gpu}")
