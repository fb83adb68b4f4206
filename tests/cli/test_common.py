"""The exit-code table of the CLI (simlunar.cli.common): each exception to its code and its one
line; input errors as user errors only inside ``user_input``; a swallowed Ctrl-C still exits 130."""

from __future__ import annotations

import errno

import pytest
import typer

from simlunar.cli import common
from simlunar.cli.common import (
    EXIT_INFRA,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_PIPE,
    EXIT_USER,
    closed_stdout,
    exit_for,
    flag,
    user_errors,
    user_input,
)
from simlunar.errors import SimlunarError


@pytest.fixture
def no_interrupt(monkeypatch):
    monkeypatch.setattr("simlunar.interrupts.interrupted", lambda: False)


def test_the_exit_codes():
    # the table of simlunar.cli's docstring; 141 = 128 + SIGPIPE (13), as a shell reports it
    assert (EXIT_INTERNAL, EXIT_USER, EXIT_INFRA, EXIT_INTERRUPTED, EXIT_PIPE) == (
        1,
        2,
        3,
        130,
        141,
    )


def test_a_user_error_is_one_line_with_multi_line_messages_joined(capsys, no_interrupt):
    out = exit_for(SimlunarError("first line\n   second line\n"))
    assert out.exit_code == EXIT_USER
    assert capsys.readouterr().err == "error: first line second line\n"


def test_an_os_error_naming_a_file_is_the_environment(capsys, no_interrupt):
    exc = PermissionError(errno.EACCES, "Permission denied", "/results/x.csv")
    assert exit_for(exc).exit_code == EXIT_INFRA
    assert capsys.readouterr().err == "error: /results/x.csv: Permission denied\n"


def test_a_full_disk_is_the_environment_even_without_a_file(capsys, no_interrupt):
    exc = OSError(errno.ENOSPC, "No space left on device")
    assert exit_for(exc).exit_code == EXIT_INFRA
    assert capsys.readouterr().err == "error: No space left on device\n"


@pytest.mark.parametrize(
    "exc", [OSError(errno.EBADF, "Bad file descriptor"), RuntimeError("oops"), ValueError("v")]
)
def test_anything_else_is_a_bug_with_its_traceback(exc, capsys, no_interrupt):
    assert exit_for(exc).exit_code == EXIT_INTERNAL
    err = capsys.readouterr().err
    assert f"simlunar: internal error ({type(exc).__name__}); this is a bug in simlunar" in err
    assert f"{type(exc).__name__}: " in err and common.REPORT_URL in err


def test_a_ctrl_c_decides_the_exit_whatever_it_caused(capsys, monkeypatch):
    monkeypatch.setattr("simlunar.interrupts.interrupted", lambda: False)
    assert exit_for(KeyboardInterrupt()).exit_code == EXIT_INTERRUPTED
    assert capsys.readouterr().err == "interrupted\n"
    # Dr.Jit turning the Ctrl-C into another error: the flag says it was an interrupt
    monkeypatch.setattr("simlunar.interrupts.interrupted", lambda: True)
    assert exit_for(NameError("_drjit_ext")).exit_code == EXIT_INTERRUPTED
    assert capsys.readouterr().err == "interrupted\n"


def test_system_exit_passes_through(no_interrupt):
    with pytest.raises(SystemExit):
        exit_for(SystemExit(4))


def test_a_closed_stdout_is_quiet(tmp_path, monkeypatch, capsys, no_interrupt):
    # closed_stdout points the stdout descriptor at /dev/null: give it a file of its own
    with open(tmp_path / "stdout", "w") as fake:
        monkeypatch.setattr("sys.stdout", fake)
        out = exit_for(BrokenPipeError(errno.EPIPE, "Broken pipe"))
        assert out.exit_code == EXIT_PIPE
        assert closed_stdout().exit_code == EXIT_PIPE
    assert capsys.readouterr().err == ""


def test_user_input_turns_value_and_os_errors_into_user_errors(tmp_path):
    with pytest.raises(SimlunarError, match=r"^bad density '1/0'$"):
        with user_input():
            raise ValueError("bad density '1/0'")
    missing = tmp_path / "nope.yaml"
    with pytest.raises(SimlunarError, match=f"^{missing}: No such file or directory$"):
        with user_input():
            open(missing)
    same = SimlunarError("kept")
    with pytest.raises(SimlunarError) as info:
        with user_input():
            raise same
    assert info.value is same
    with pytest.raises(TypeError):  # a bug stays a bug
        with user_input():
            raise TypeError("not input")


def test_an_empty_message_names_the_exception():
    with pytest.raises(SimlunarError, match=r"^ValueError$"):
        with user_input():
            raise ValueError()


def test_user_errors_maps_a_commands_exceptions(capsys, no_interrupt):
    @user_errors
    def command(x):
        """Doc."""
        if x == "bad":
            raise SimlunarError("bad x")
        return x * 2

    assert command(2) == 4
    assert command.__doc__ == "Doc." and command.__name__ == "command"
    with pytest.raises(typer.Exit) as info:
        command("bad")
    assert info.value.exit_code == EXIT_USER
    assert capsys.readouterr().err == "error: bad x\n"


def test_user_errors_exits_130_after_a_swallowed_ctrl_c(capsys, monkeypatch):
    monkeypatch.setattr("simlunar.interrupts.interrupted", lambda: True)

    @user_errors
    def command():
        return "done"  # the interrupt was caught inside and the command went on

    with pytest.raises(typer.Exit) as info:
        command()
    assert info.value.exit_code == EXIT_INTERRUPTED

    @user_errors
    def exits():
        raise typer.Exit(0)

    with pytest.raises(typer.Exit) as info:
        exits()
    assert info.value.exit_code == EXIT_INTERRUPTED


def test_flag_is_off_by_default_without_a_shown_default():
    opt = flag("--short", "One line only.")
    assert opt.default is False and opt.show_default is False
    assert opt.param_decls == ("--short",) and opt.help == "One line only."
