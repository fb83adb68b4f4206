"""What the commands share: exceptions mapped to exit codes, the shape of an off-by-default
flag.

Exit codes (the table is in :mod:`simlunar.cli`): 0 done, 1 a bug, 2 a user error, 3 the
environment failed, 130 interrupted, 141 stdout closed early in a write that is not a
command's own (a command prints through :func:`echo`, which lets its work finish).
"""

from __future__ import annotations

import contextlib
import errno
import functools
import os
import sys
import traceback
from typing import Any

import typer

from simlunar import interrupts
from simlunar.errors import InfrastructureError, RunInterrupted, SimlunarError

__all__ = [
    "EXIT_INFRA",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_PIPE",
    "EXIT_USER",
    "closed_stdout",
    "echo",
    "exit_for",
    "flag",
    "user_errors",
    "user_input",
]

EXIT_USER, EXIT_INTERNAL, EXIT_INFRA, EXIT_INTERRUPTED = 2, 1, 3, 130
#: exit code when stdout is found closed outside :func:`echo` (click's ``--help``): quiet, as a
#: shell reports a program ended by SIGPIPE (128 + 13)
EXIT_PIPE = 141
REPORT_URL = "https://github.com/simlunar/simlunar/issues"


def flag(name: str, help: str) -> Any:
    """An off-by-default switch ``name`` (its help shows no ``[default: False]``)."""
    return typer.Option(False, name, help=help, show_default=False)


#: errors that mean "the user's input is wrong" when raised while the input is being read
#: and checked (inside :func:`user_input`); raised later, they are bugs
INPUT_ERRORS: tuple[type[BaseException], ...] = (ValueError, OSError)


@contextlib.contextmanager
def user_input():
    """Treat ValueError / OSError raised inside (reading and checking input) as user errors."""
    try:
        yield
    except SimlunarError:
        raise
    except INPUT_ERRORS as exc:
        raise SimlunarError(_one_line(exc)) from None


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.filename is not None and exc.strerror:
        return f"{exc.filename}: {exc.strerror}"
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    msg = " ".join(m.strip() for m in str(exc).strip().splitlines())
    return msg or type(exc).__name__


#: errno values that mean the environment failed (exit 3), even when no file is named
ENVIRONMENT_ERRNOS = frozenset(
    getattr(errno, name) for name in ("ENOSPC", "EDQUOT", "EROFS", "EIO") if hasattr(errno, name)
)


def user_errors(fn):
    """Map exceptions to the exit codes above (one line on stderr except for bugs)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            out = fn(*args, **kwargs)
        except typer.Exit as exc:
            if interrupts.interrupted() and exc.exit_code != EXIT_INTERRUPTED:
                raise exit_for(KeyboardInterrupt()) from None
            raise
        except BaseException as exc:
            raise exit_for(exc) from None
        if interrupts.interrupted():  # a Ctrl-C that the interrupted code swallowed
            raise exit_for(KeyboardInterrupt())
        return out

    return wrapper


def exit_for(exc: BaseException) -> typer.Exit:
    """Print the line for ``exc`` and return the :class:`typer.Exit` of its exit code.

    A Ctrl-C decides the exit whatever exception it caused (:mod:`simlunar.interrupts`).
    """
    if isinstance(exc, KeyboardInterrupt) or interrupts.interrupted():
        msg = _one_line(exc) if isinstance(exc, RunInterrupted) and str(exc) else "interrupted"
        typer.echo(msg, err=True)
        return typer.Exit(EXIT_INTERRUPTED)
    if isinstance(exc, BrokenPipeError):
        return closed_stdout()
    if isinstance(exc, SimlunarError):
        typer.echo(f"error: {_one_line(exc)}", err=True)
        return typer.Exit(EXIT_USER)
    if isinstance(exc, InfrastructureError):
        typer.echo(f"error: {_one_line(exc)}", err=True)
        return typer.Exit(EXIT_INFRA)
    if isinstance(exc, OSError):
        if exc.filename is None and exc.errno not in ENVIRONMENT_ERRNOS:
            return _internal(exc)
        # a write refused after the checks passed (disk full, quota, read-only file
        # system, I/O error, permissions changed); the OS names no file for a full disk
        typer.echo(f"error: {_one_line(exc)}", err=True)
        return typer.Exit(EXIT_INFRA)
    if isinstance(exc, (SystemExit, GeneratorExit)):
        raise exc
    return _internal(exc)


def echo(message: str = "") -> None:
    """``typer.echo`` of a line to stdout that survives a reader who went away
    (``simlunar run ... | head -1``): the first write that finds the pipe closed sends stdout
    to the null device, and the command goes on with its work (nothing more is printed) and
    ends with the exit code it would have had. Every command's stdout line goes through here."""
    try:
        typer.echo(message)
    except BrokenPipeError:
        closed_stdout()


def closed_stdout() -> typer.Exit:
    """stdout's reader went away: nothing more can be said there, and nothing on stderr."""
    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # the interpreter's last flush must not fail
    return typer.Exit(EXIT_PIPE)


def _internal(exc: BaseException) -> typer.Exit:
    traceback.print_exception(exc, file=sys.stderr)
    typer.echo(
        f"simlunar: internal error ({type(exc).__name__}); this is a bug in simlunar, please "
        f"report it with the traceback above at {REPORT_URL}",
        err=True,
    )
    return typer.Exit(EXIT_INTERNAL)
