"""The progress of a run (units done, cached, and inside the current unit its open stages
with their totals: frames of a scan, beams, acquisitions of a study, steps): a live bar per
stage on a terminal, and plain lines where stderr is a file or a pipe (``simlunar run ... 2>
run.log``, a batch job), where a live bar would print nothing until the run ends.

The stages come from the library as :class:`simlunar.progress.Event` (the unit reports them
when it runs in this process: serially, or a single unit with ``--workers``)."""

from __future__ import annotations

import sys
import time

from simlunar.progress import Event

__all__ = ["unit_fraction"]


class _Bar:
    """Live bars on stderr: the units, then one indented bar per open stage of the unit."""

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
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[unit]}"),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=Console(stderr=True),
            transient=False,
        )
        self.task = self.p.add_task(f"[bold]{name}[/]", total=total, completed=done, unit="units")
        self.units_done = done
        self.stages: dict[tuple, int] = {}  # open stage path -> its bar
        self.open: dict[tuple, Event] = {}
        self.p.start()

    def event(self, ev: Event) -> None:
        """Show a stage of the current unit (its bar added, updated or removed)."""
        if ev.finished:
            self._close(ev.path)
        else:
            self._show(ev)
        # the units bar moves inside a unit too, so a one-unit run has an ETA
        self.p.update(self.task, completed=self.units_done + unit_fraction(self.open.values()))

    def _show(self, ev: Event) -> None:
        self.open[ev.path] = ev
        task = self.stages.get(ev.path)
        if task is None:
            label = "  " * (ev.depth + 1) + ev.stage
            task = self.p.add_task(label, total=ev.total, completed=ev.done, unit=ev.unit)
            self.stages[ev.path] = task
        else:
            self.p.update(task, completed=ev.done, total=ev.total)

    def stage(self, name: str, done: int, total: int) -> None:
        """A one-level stage (the older form of :meth:`event`)."""
        self.event(Event((name,), done, total, "steps"))

    def _close(self, path: tuple) -> None:
        self.open = {p: e for p, e in self.open.items() if p[: len(path)] != path}
        for p in [p for p in self.stages if p[: len(path)] == path]:
            self.p.remove_task(self.stages.pop(p))

    def advance(self) -> None:
        self.units_done += 1
        self._close(())
        self.p.update(self.task, completed=self.units_done)

    def stop(self) -> None:
        self.p.stop()


class _Lines:
    """Progress as lines on a stream: one per finished unit (with elapsed time and an ETA from
    the units computed so far), and the current unit's open stages (outermost first, each
    with its count and total) at most once per ``every_s``."""

    def __init__(self, total: int, done: int, name: str, *, stream=None, every_s: float = 30.0):
        self.total, self.done, self.name = total, done, name
        self.stream = sys.stderr if stream is None else stream
        self.every_s = every_s
        self.t0 = time.monotonic()
        self.unit_t0 = self.t0
        self.n_new = 0
        self.last_stage = self.t0
        self.open: dict[tuple, Event] = {}
        self._say(f"{done}/{total} units ({done} cached)")

    def _say(self, text: str) -> None:
        print(f"{self.name}: {text}", file=self.stream, flush=True)

    def event(self, ev: Event) -> None:
        if ev.finished:
            self.open = {p: e for p, e in self.open.items() if p[: len(ev.path)] != ev.path}
        else:
            self.open[ev.path] = ev
        now = time.monotonic()
        if self.open and now - self.last_stage >= self.every_s:
            self.last_stage = now
            stages = " > ".join(e.text() for e in self.open.values())
            self._say(f"unit {self.done + 1}/{self.total}: {stages}{self._unit_eta(now)}")

    def _unit_eta(self, now: float) -> str:
        """``", unit 38 %, ETA 0:05:00"``: this unit's share done, and the time left for it
        and the units after it (at this unit's pace); empty before anything is done."""
        frac = unit_fraction(self.open.values())
        if frac <= 0.0:
            return ""
        per_unit = (now - self.unit_t0) / frac
        left = per_unit * (1.0 - frac) + per_unit * (self.total - self.done - 1)
        return f", unit {100 * frac:.0f} %, ETA {_clock(left)}"

    def stage(self, name: str, done: int, total: int) -> None:
        """A one-level stage (the older form of :meth:`event`)."""
        self.event(Event((name,), done, total, "steps"))

    def advance(self) -> None:
        self.done += 1
        self.n_new += 1
        self.open = {}
        elapsed = time.monotonic() - self.t0
        self.last_stage = self.unit_t0 = time.monotonic()
        left = (self.total - self.done) * elapsed / self.n_new
        eta = f", ETA {_clock(left)}" if self.done < self.total else ""
        self._say(f"{self.done}/{self.total} units, {_clock(elapsed)} elapsed{eta}")

    def stop(self) -> None:
        pass


def unit_fraction(open_stages) -> float:
    """How much of the current unit is done, read from its open stages (0 to 1).

    The outermost stage counts ``done / total``; a stage opened inside it adds its own
    fraction of one of the outer stage's items, and so on inward (``study 1/4 steps >
    scan 11/22 frames`` is (1 + 0.5) / 4 = 0.375). A stage without a total adds nothing.

    Parameters
    ----------
    open_stages : iterable of Event
        The unit's open stages (any order; one per depth, as the library opens them).
    """
    chain = sorted(open_stages, key=lambda e: e.depth)
    frac = 0.0
    for ev in reversed(chain):
        if not ev.total:
            frac = 0.0
            continue
        frac = min(1.0, (min(ev.done, ev.total) + frac) / ev.total)
    return frac


def _clock(seconds: float) -> str:
    s = round(seconds)
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


def _progress(enabled: bool, total: int, done: int, name: str) -> _Bar | _Lines | None:
    if not enabled:
        return None
    if not sys.stderr.isatty():
        return _Lines(total, done, name)
    return _Bar(total, done, name)
