"""Command-line interface (Typer): a thin front over the library and the pipeline.

Exit codes: 0 done; 2 a user error (bad option, config, input file or result folder), found
before anything is written, reported as one line ``error: ...`` without a traceback; 3 the
environment failed during a run (Dask scheduler or workers lost, a write refused): one line,
finished units kept; 130 interrupted (Ctrl-C): one line saying what was kept and how to
resume; 1 an internal error (a bug): the traceback and a line asking to report it. A reader
that closes stdout early (``simlunar render ... | head -1``) stops the printing, not the work:
every command prints through :func:`~simlunar.cli.common.echo` and ends as it would have
(141, quiet, only when the pipe broke in a write of click's own: ``--help``).

A command is the function of its name in its module (:data:`COMMANDS`: one module per command
or group of commands that need the same library), whose top imports Typer and the signature's
needs only: the library is imported when the command runs (by ``run`` and ``figures`` through
:mod:`simlunar.cli.run_actions`, which imports it at its top); every command runs inside
:func:`~simlunar.cli.common.user_errors`. The root command imports a
command's module only when that command is invoked (or its help asked for): ``simlunar --help``
and ``--version`` need Typer alone, where the modules behind the commands (the scientific
stack, the pydantic models, Mitsuba's backend) take seconds to import.
"""

from __future__ import annotations

import importlib
import os
import sys

import typer
from typer.core import TyperCommand, TyperGroup

import simlunar
from simlunar import interrupts
from simlunar.cli.common import (
    EXIT_INFRA,
    EXIT_INTERRUPTED,
    EXIT_PIPE,
    EXIT_USER,
    closed_stdout,
    echo,
    exit_for,
    user_errors,
)

__all__ = ["COMMANDS", "app", "main"]

#: command -> (its module in simlunar.cli, its docstring: the line ``simlunar --help`` shows),
#: in the order listed (tests/pipeline/test_cli.py checks the lines against the docstrings)
COMMANDS = {
    "doctor": (
        "doctor",
        "Versions, the chosen Mitsuba variant and why, libLLVM, kernel cache, cores, GPU.",
    ),
    "run": (
        "run",
        "Run (or resume) an experiment: results.csv, scores.md/.tex, provenance.json, figures/.",
    ),
    "train": (
        "train",
        "Train a learned map or reconstruction: <model>.joblib and its record <model>.json.",
    ),
    "figures": (
        "run",
        "Draw the figures of a result folder without recomputing (only those whose inputs "
        "changed).",
    ),
    "report": (
        "report",
        "Write report.html of a result folder: config, versions, tables, figures, timings.",
    ),
    "schema": (
        "schema",
        "JSON Schema of experiment (scene, preset) YAMLs (for editors: yaml-language-server).",
    ),
    "render": (
        "render",
        "Render a scene: radiance.exr (linear), preview.png, ground_truth.exr/.npz, scene.json.",
    ),
    "terrain": (
        "terrain",
        "Generate a terrain: dem.<fmt>, albedo.png, hillshade.png, mesh.ply, features.json.",
    ),
}


class _Pending(TyperCommand):
    """A command whose module is not imported yet: its name and help line only."""


class _LazyGroup(TyperGroup):
    """The root command: each command stands as a :class:`_Pending` until it is looked up."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name, (_, line) in COMMANDS.items():
            self.add_command(_Pending(name, help=line))

    def get_command(self, ctx, cmd_name):
        cmd = super().get_command(ctx, cmd_name)
        if isinstance(cmd, _Pending):
            cmd = self.commands[cmd_name] = _load(cmd_name)
        return cmd

    def format_commands(self, ctx, formatter):
        # TyperGroup's listing looks every command up (importing them all) for its help line
        limit = formatter.width - 6 - max(map(len, self.commands))
        rows = [(name, cmd.get_short_help_str(limit)) for name, cmd in self.commands.items()]
        with formatter.section("Commands"):
            formatter.write_dl(rows)


def _load(name: str):
    """The click command ``name``, its module imported (a failure there exits as a failure
    inside the command would: a bug with its traceback, a Ctrl-C as interrupted)."""
    try:
        module = importlib.import_module(f"{__name__}.{COMMANDS[name][0]}")
    except BaseException as exc:
        raise exit_for(exc) from None
    one = typer.Typer(add_completion=False, rich_markup_mode=None)
    one.command(name=name)(user_errors(getattr(module, name)))
    return typer.main.get_command(one)


app = typer.Typer(
    cls=_LazyGroup,
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    # plain click help: rich markup would swallow the "[default: ...]" of the help strings
    # and print "<bool>" after every flag (the commands' own too, in _load)
    rich_markup_mode=None,
    help="simlunar: image-directed range scanning of lunar terrain, simulated.",
)


def _version(value: bool) -> None:
    if value:
        echo(f"simlunar {simlunar.__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False,
        "--version",
        callback=_version,
        is_eager=True,
        help="Print the version and exit.",
        show_default=False,
    ),
) -> None:
    """simlunar: image-directed range scanning of lunar terrain, simulated."""


def _usage_errors():
    """Typer's click exceptions module (vendored as ``typer._click`` by newer Typer)."""
    try:
        from typer._click import exceptions
    except ImportError:  # Typer on the click package
        from click import exceptions
    return exceptions


def main() -> None:
    cx = _usage_errors()

    interrupts.clear()
    interrupts.install()
    try:
        code = app(prog_name="simlunar", standalone_mode=False)
        code = code if isinstance(code, int) else 0
    except cx.NoArgsIsHelpError as exc:
        echo(exc.ctx.get_help() if exc.ctx else str(exc))
        code = EXIT_USER
    except cx.UsageError as exc:
        # one line (click draws a box of 5-6 lines): the command, the problem, where to look
        where = exc.ctx.command_path if exc.ctx else "simlunar"
        msg = " ".join(exc.format_message().split())
        typer.echo(f"error: {where}: {msg} (see {where} --help)", err=True)
        code = EXIT_USER
    except typer.Exit as exc:
        code = exc.exit_code
    except (KeyboardInterrupt, typer.Abort):
        typer.echo("interrupted", err=True)
        code = EXIT_INTERRUPTED
    except BrokenPipeError:
        code = closed_stdout().exit_code
    if interrupts.interrupted() and code not in (EXIT_INTERRUPTED, EXIT_PIPE):
        typer.echo("interrupted", err=True)  # after the command's own handling
        code = EXIT_INTERRUPTED
    try:
        sys.stdout.flush()
    except (BrokenPipeError, ValueError):
        code = closed_stdout().exit_code if code == 0 else code
    sys.stderr.flush()
    if code in (EXIT_INFRA, EXIT_INTERRUPTED):
        # threads of units still running (and their forked study processes) would be
        # waited for at interpreter exit; the message is out and the lock released
        os._exit(code)
    sys.exit(code)
