"""Command-line interface (Typer): a thin front over the library and the pipeline.

Every user error (bad option, bad file, bad config) prints one line ``error: ...`` and exits
with code 2, without a traceback.
"""

from __future__ import annotations

import functools
import os
import platform
import sys

import typer

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="simlunar: image-directed range scanning of lunar terrain, simulated.")

@app.callback()
def _root() -> None:
    """simlunar: image-directed range scanning of lunar terrain, simulated."""


USER_ERRORS: tuple[type[BaseException], ...] = (ValueError, FileNotFoundError, KeyError,
                                                 IsADirectoryError, PermissionError)


def user_errors(fn):
    """Turn user errors into one line on stderr and exit code 2."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except typer.Exit:
            raise
        except USER_ERRORS as exc:
            msg = str(exc).strip().splitlines()
            typer.echo(f"error: {' '.join(m.strip() for m in msg) or type(exc).__name__}",
                       err=True)
            raise typer.Exit(2) from None

    return wrapper


@app.command()
@user_errors
def doctor(short: bool = typer.Option(False, "--short", help="One line only.")) -> None:
    """Versions, the chosen Mitsuba variant and why, libLLVM, kernel cache, cores, GPU."""
    from simlunar.render import backend

    info = backend.choose_variant()
    if short:
        typer.echo(f"simlunar doctor: variant {info.variant} ({info.reason})")
        return
    vers = backend.versions()
    typer.echo("simlunar doctor")
    for k, v in vers.items():
        typer.echo(f"  {k:<15} {v}")
    typer.echo(f"  {'variant':<15} {info.variant}")
    typer.echo(f"  {'why':<15} {info.reason}")
    for k, v in info.probes.items():
        typer.echo(f"  {'probe ' + k:<15} {v}")
    typer.echo(f"  {'libLLVM':<15} {info.libllvm or 'none'}")
    typer.echo(f"  {'kernel cache':<15} {info.cache_dir}")
    typer.echo(f"  {'cores':<15} {os.cpu_count()}")
    typer.echo(f"  {'machine':<15} {platform.machine()} {platform.system()}")
    gpu = "CUDA device present" if backend._cuda_present() else "none"
    typer.echo(f"  {'GPU':<15} {gpu}")


def main() -> None:
    app(prog_name="simlunar")


if __name__ == "__main__":
    sys.exit(main())
