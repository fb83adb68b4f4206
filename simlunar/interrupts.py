"""One rule for Ctrl-C (SIGINT) from the first byte a command writes to the last.

The CLI installs :func:`install`: the handler records the interrupt in a flag before raising
``KeyboardInterrupt`` as Python's own does. The flag, not the exception, decides the exit
(130 with the usual line): code that catches ``KeyboardInterrupt`` or turns it into another
exception (Mitsuba / Dr.Jit while they import and initialise: ``NameError: _drjit_ext``,
aborts) cannot change the outcome. Regions that must not be interrupted half-way (importing
the renderer) run under :func:`deferred`: a Ctrl-C there is recorded and raised when the
region ends.
"""

from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["clear", "deferred", "install", "interrupted"]

_HIT = threading.Event()
_DEFERRING = threading.Event()


def _handler(signum, frame):
    _HIT.set()
    if _DEFERRING.is_set():
        return  # raised when the deferred region ends
    raise KeyboardInterrupt


def install() -> None:
    """Route SIGINT through the flag (main thread only; a no-op elsewhere)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, _handler)


def installed() -> bool:
    return signal.getsignal(signal.SIGINT) is _handler


def interrupted() -> bool:
    """Whether a Ctrl-C reached this process since :func:`install` / :func:`clear`."""
    return _HIT.is_set()


def clear() -> None:
    _HIT.clear()


@contextlib.contextmanager
def deferred():
    """Hold a Ctrl-C during the block (recorded at once, raised as ``KeyboardInterrupt`` when
    the block ends). Only where :func:`install` routed SIGINT here and on the main thread (a
    signal never interrupts another thread)."""
    if not installed() or threading.current_thread() is not threading.main_thread():
        yield
        return
    _DEFERRING.set()
    try:
        yield
    finally:
        _DEFERRING.clear()
    if _HIT.is_set():
        raise KeyboardInterrupt
