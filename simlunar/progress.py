"""Progress inside a long computation: named stages with done / total, for whoever listens.

The library reports into this channel without knowing who shows it: a study opens a stage
(``with stage("scanner study", total=5, unit="steps") as s: ... s.advance()``), code deeper
down opens nested stages (the frames of one coded scan, the beams of one LIDAR acquisition)
or advances the innermost open stage (:func:`advance`: the capture counts each sensed frame).
A listener installed with :func:`reporting` (the CLI's progress bar or log lines, a test's
recorder) receives every change as an :class:`Event`. Without a listener every call is a
no-op costing a context-variable lookup.

The channel lives in a :class:`contextvars.ContextVar`: each thread (each work unit of a
thread pool) has its own, and a forked worker process inherits a listener that it never
calls (events are only delivered in the process that installed it; a fork's parent reports
its children's progress as their results come back).

Arrays only, no files: this module imports nothing of simlunar.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass

__all__ = ["Event", "Stage", "advance", "reporting", "stage"]


@dataclass(frozen=True)
class Event:
    """One change of an open stage.

    Attributes
    ----------
    path : tuple of str
        Names of the open stages, outermost first; this event's stage is the last.
    done : int
        Items finished in this stage.
    total : int or None
        Items the stage has (None: not known in advance).
    unit : str
        What the items are (``"frames"``, ``"beams"``, ``"acquisitions"``, ``"steps"``).
    finished : bool
        The stage has closed (normally with ``done == total``; an exception or a Ctrl-C
        closes it early).
    """

    path: tuple[str, ...]
    done: int
    total: int | None
    unit: str
    finished: bool = False

    @property
    def stage(self) -> str:
        """The stage's own name (the last of :attr:`path`)."""
        return self.path[-1]

    @property
    def depth(self) -> int:
        """0 for an outermost stage, 1 for a stage opened inside it, ..."""
        return len(self.path) - 1

    def text(self) -> str:
        """``"name 3/10 frames"`` (``"name 3 frames"`` without a total)."""
        count = f"{self.done}/{self.total}" if self.total is not None else f"{self.done}"
        return f"{self.stage} {count} {self.unit}"


class _Channel:
    def __init__(self, callback: Callable[[Event], None]):
        self.callback = callback
        self.pid = os.getpid()
        self.open: list[Stage] = []

    def send(self, event: Event) -> None:
        if os.getpid() == self.pid:  # never from a forked child
            self.callback(event)


_CHANNEL: contextvars.ContextVar[_Channel | None] = contextvars.ContextVar(
    "simlunar_progress", default=None
)


@contextlib.contextmanager
def reporting(callback: Callable[[Event], None] | None) -> Iterator[None]:
    """Deliver the progress events of the block (this thread) to ``callback(event)``.

    ``None`` leaves the block silent (and hides an outer listener). Nested ``reporting``
    blocks replace the listener for their duration.
    """
    token = _CHANNEL.set(None if callback is None else _Channel(callback))
    try:
        yield
    finally:
        _CHANNEL.reset(token)


class Stage:
    """An open stage: :meth:`advance` it as items finish (see :func:`stage`)."""

    def __init__(self, channel: _Channel | None, path: tuple[str, ...], total, unit: str, done):
        self._channel = channel
        self.path = path
        self.total = None if total is None else int(total)
        self.unit = unit
        self.done = int(done)

    def _send(self, finished: bool = False) -> None:
        if self._channel is not None:
            self._channel.send(Event(self.path, self.done, self.total, self.unit, finished))

    def advance(self, n: int = 1) -> None:
        """``n`` more items finished."""
        self.done += int(n)
        self._send()

    def update(self, done: int, total: int | None = None) -> None:
        """Set the count (and the total, once known)."""
        self.done = int(done)
        if total is not None:
            self.total = int(total)
        self._send()


@contextlib.contextmanager
def stage(name: str, total: int | None = None, *, unit: str = "steps", done: int = 0):
    """Open a stage for the block, nested in the stage open around it (if any).

    Parameters
    ----------
    name : str
        What the stage does (``"gray_code scan"``, ``"sampling study"``).
    total : int, optional
        Items it has; None when not known in advance.
    unit : str
        What the items are, plural.
    done : int
        Items already finished when it opens (restored from a checkpoint).

    Yields
    ------
    Stage
    """
    channel = _CHANNEL.get()
    parent = channel.open[-1].path if channel is not None and channel.open else ()
    s = Stage(channel, (*parent, str(name)), total, unit, done)
    if channel is None:
        yield s
        return
    channel.open.append(s)
    s._send()
    try:
        yield s
    finally:
        channel.open.remove(s)
        s._send(finished=True)


def advance(n: int = 1, *, unit: str | None = None) -> None:
    """Advance the innermost open stage by ``n`` (when ``unit`` is given, only if that stage
    counts ``unit``: a capture counts frames into a frames stage, never into another)."""
    channel = _CHANNEL.get()
    if channel is None or not channel.open:
        return
    s = channel.open[-1]
    if unit is None or s.unit == unit:
        s.advance(n)
