"""The error classes: which ``except`` clause catches each, and the exit code the CLI gives it."""

from __future__ import annotations

import pytest
import typer

from simlunar.cli.common import EXIT_INFRA, EXIT_INTERRUPTED, EXIT_USER, exit_for
from simlunar.errors import (
    ConfigError,
    InfrastructureError,
    NothingMeasuredError,
    ResultFolderError,
    RunInterrupted,
    SimlunarError,
)


def test_user_errors_are_simlunar_errors_and_bad_values_are_value_errors():
    # the library raises ValueError for bad input; config and measuring errors stay catchable
    # that way, and the CLI reports every SimlunarError as a user error
    for cls in (ConfigError, ResultFolderError, NothingMeasuredError):
        assert issubclass(cls, SimlunarError)
    assert issubclass(ConfigError, ValueError)
    assert issubclass(NothingMeasuredError, ValueError)
    assert not issubclass(ResultFolderError, ValueError)
    with pytest.raises(ValueError, match=r"study\.trials: must be >= 1"):
        raise ConfigError("study.trials: must be >= 1")


def test_the_environment_failing_is_not_the_users_input():
    assert not issubclass(InfrastructureError, SimlunarError)
    assert issubclass(InfrastructureError, Exception)


def test_an_interrupted_run_escapes_except_exception():
    # library code that catches Exception (a unit failing) must not swallow a Ctrl-C
    assert issubclass(RunInterrupted, KeyboardInterrupt)
    assert not issubclass(RunInterrupted, Exception)
    with pytest.raises(RunInterrupted):
        try:
            raise RunInterrupted("kept 2 units")
        except Exception:  # pragma: no cover - the point of the test is that this never runs
            pytest.fail("RunInterrupted was caught as an Exception")


@pytest.mark.parametrize(
    ("exc", "code", "line"),
    [
        (SimlunarError("bad option"), EXIT_USER, "error: bad option"),
        (ConfigError("render.spp: must be > 0"), EXIT_USER, "error: render.spp: must be > 0"),
        (
            ResultFolderError("out: owned by another run"),
            EXIT_USER,
            "error: out: owned by another run",
        ),
        (NothingMeasuredError("nothing decoded"), EXIT_USER, "error: nothing decoded"),
        (InfrastructureError("scheduler lost"), EXIT_INFRA, "error: scheduler lost"),
        (
            RunInterrupted("kept 3 of 4 units; resume with the same command"),
            EXIT_INTERRUPTED,
            "kept 3 of 4 units; resume with the same command",
        ),
    ],
    ids=lambda v: type(v).__name__ if isinstance(v, BaseException) else None,
)
def test_each_error_has_its_exit_code_and_one_line(exc, code, line, capsys, monkeypatch):
    monkeypatch.setattr("simlunar.interrupts.interrupted", lambda: False)
    out = exit_for(exc)
    assert isinstance(out, typer.Exit) and out.exit_code == code
    assert capsys.readouterr().err == line + "\n"
