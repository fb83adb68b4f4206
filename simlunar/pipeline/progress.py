"""The progress bar of a run (units done, cached, the current unit's stage)."""

from __future__ import annotations

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


def _progress(enabled: bool, total: int, done: int, name: str) -> _Bar | None:
    return _Bar(total, done, name) if enabled else None
