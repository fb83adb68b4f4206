"""Ctrl-C (SIGINT) through the flag of :mod:`simlunar.interrupts`: raised at once, or held to the
end of a deferred region; the flag survives code that swallows the exception."""

from __future__ import annotations

import signal
import threading

import pytest

from simlunar import interrupts


@pytest.fixture
def sigint():
    """Restore pytest's SIGINT handler and a clear flag around each test."""
    before = signal.getsignal(signal.SIGINT)
    interrupts.clear()
    yield
    signal.signal(signal.SIGINT, before)
    interrupts.clear()


def _ctrl_c():
    signal.raise_signal(signal.SIGINT)


def test_install_routes_sigint_through_the_flag(sigint):
    assert not interrupts.installed()
    interrupts.install()
    assert interrupts.installed()
    assert not interrupts.interrupted()
    with pytest.raises(KeyboardInterrupt):
        _ctrl_c()
    assert interrupts.interrupted()
    interrupts.clear()
    assert not interrupts.interrupted()


def test_the_flag_outlives_a_swallowed_keyboard_interrupt(sigint):
    interrupts.install()
    try:
        _ctrl_c()
    except KeyboardInterrupt:
        pass  # e.g. Dr.Jit turning it into another error while it initialises
    assert interrupts.interrupted()


def test_deferred_holds_the_interrupt_to_the_end_of_the_region(sigint):
    interrupts.install()
    reached = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts.deferred():
            _ctrl_c()
            assert interrupts.interrupted()  # recorded at once
            reached.append("after the signal")
    assert reached == ["after the signal"]
    assert interrupts.interrupted()


def test_deferred_without_an_interrupt_raises_nothing(sigint):
    interrupts.install()
    with interrupts.deferred():
        x = 1
    assert x == 1 and not interrupts.interrupted()
    # and the region ended: a later Ctrl-C raises at once again
    reached = []
    with pytest.raises(KeyboardInterrupt):
        _ctrl_c()
        reached.append("never")
    assert reached == []


def test_deferred_is_a_plain_block_where_install_did_not_route_sigint(sigint):
    signal.signal(signal.SIGINT, signal.default_int_handler)
    reached = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts.deferred():
            _ctrl_c()
            reached.append("never")
    assert reached == []
    assert not interrupts.interrupted()  # Python's own handler sets no flag


def test_install_off_the_main_thread_changes_nothing(sigint):
    before = signal.getsignal(signal.SIGINT)
    t = threading.Thread(target=interrupts.install)
    t.start()
    t.join()
    assert signal.getsignal(signal.SIGINT) is before


def test_deferred_off_the_main_thread_just_runs_the_block(sigint):
    interrupts.install()
    seen = []

    def work():
        with interrupts.deferred():
            seen.append(interrupts._DEFERRING.is_set())

    t = threading.Thread(target=work)
    t.start()
    t.join()
    assert seen == [False]
