"""The progress of a run (units done, cached, the current unit's stage): a live bar on a
terminal, and plain lines where stderr is a file or a pipe (``simlunar run ... 2> run.log``,
a batch job), where a live bar would print nothing until the run ends."""

from __future__ import annotations

import sys
import time

__all__ = []


class _Bar:
    def __init__(self, total: int, done: int, name: str):
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.p = Progress(
            TextColumn(f"[bold]{name}[/] units"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=Console(stderr=True),
            transient=False,
        )
        self.task = self.p.add_task("units", total=total, completed=done)
        self.sub = None
        self.p.start()

    def stage(self, name: str, done: int, total: int) -> None:
        """Within-unit progress (in-process runs only): a second bar for the current stage."""
        if self.sub is None:
            self.sub = self.p.add_task(name, total=total)
        self.p.update(self.sub, completed=done, total=total, description=name)

    def advance(self) -> None:
        self.p.advance(self.task)
        if self.sub is not None:
            self.p.remove_task(self.sub)
            self.sub = None

    def stop(self) -> None:
        self.p.stop()


class _Lines:
    """Progress as lines on a stream: one per finished unit (with elapsed time and an ETA from
    the units computed so far), and the current unit's stage at most once per ``every_s``."""

    def __init__(self, total: int, done: int, name: str, *, stream=None, every_s: float = 60.0):
        self.total, self.done, self.name = total, done, name
        self.stream = sys.stderr if stream is None else stream
        self.every_s = every_s
        self.t0 = time.monotonic()
        self.n_new = 0
        self.last_stage = self.t0
        self._say(f"{done}/{total} units ({done} cached)")

    def _say(self, text: str) -> None:
        print(f"{self.name}: {text}", file=self.stream, flush=True)

    def stage(self, name: str, done: int, total: int) -> None:
        now = time.monotonic()
        if now - self.last_stage >= self.every_s:
            self.last_stage = now
            self._say(f"unit {self.done + 1}/{self.total}: {name} {done}/{total}")

    def advance(self) -> None:
        self.done += 1
        self.n_new += 1
        elapsed = time.monotonic() - self.t0
        self.last_stage = time.monotonic()
        left = (self.total - self.done) * elapsed / self.n_new
        eta = f", ETA {_clock(left)}" if self.done < self.total else ""
        self._say(f"{self.done}/{self.total} units, {_clock(elapsed)} elapsed{eta}")

    def stop(self) -> None:
        pass


def _clock(seconds: float) -> str:
    s = round(seconds)
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


def _progress(enabled: bool, total: int, done: int, name: str) -> _Bar | _Lines | None:
    if not enabled:
        return None
    if not sys.stderr.isatty():
        return _Lines(total, done, name)
    return _Bar(total, done, name)
