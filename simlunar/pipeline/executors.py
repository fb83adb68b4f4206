"""Executors that run work units: in-process, a local pool, or a Dask cluster.

All three expose one method, :meth:`Executor.run`, that yields ``(index, result)`` as units
finish (in any order); the runner writes each result to the cache as soon as it arrives, in
the parent process, so the cache logic is the same whichever executor computed it.
"""

from __future__ import annotations

import concurrent.futures as cf
import uuid
from collections.abc import Callable, Iterator
from typing import Any


def default_workers() -> int:
    """Worker count when none is given: 1 (rendering already uses every core; ``--workers``
    adds parallel sampling studies)."""
    return 1


class Executor:
    """Base: runs ``fn(payload)`` for each payload and yields ``(index, result)``."""

    name = "base"

    def run(
        self, fn: Callable[[Any], Any], payloads: list[Any], *, progress: Callable | None = None
    ) -> Iterator[tuple[int, Any]]:
        """Yield ``(index, fn(payload))`` as units finish.

        ``progress`` (a within-unit callback ``(stage, done, total)``) is passed to ``fn`` as
        a keyword only by in-process executors: callbacks do not cross process boundaries.
        """
        raise NotImplementedError

    def describe(self) -> dict:
        return {"executor": self.name}

    def close(self) -> None:
        pass


class SerialExecutor(Executor):
    """Runs units one after another in this process."""

    name = "serial"

    def run(self, fn, payloads, *, progress=None):
        for i, p in enumerate(payloads):
            yield i, (fn(p) if progress is None else fn(p, progress=progress))


def accepts_keyword(fn, name: str) -> bool:
    """Whether ``fn``'s signature has a parameter ``name`` (False when it has no signature)."""
    import inspect

    try:
        return name in inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False


class LocalPoolExecutor(Executor):
    """``workers`` units at a time in this process; their sampling studies on forked processes.

    Each unit runs in a thread of this process, so nothing is imported, initialised or
    compiled twice, and each render still uses every core: renders of concurrent units take
    turns (a lock in :mod:`simlunar.pipeline.stages`), which costs nothing because a render
    already keeps every core busy. The single-threaded part of a unit, the sampling study,
    runs its (strategy, trial) tasks on ``workers`` forked processes
    (:func:`simlunar.study.sampling.run_sampling_study`), which is where the cores are gained;
    while one unit waits for its study, another renders. Forking is safe here because the
    forked processes only run NumPy/Numba code and never touch Mitsuba's JIT state. A sweep
    with a single unit is parallel too (its study is). Results do not depend on ``workers``.

    ``fn`` gets ``study_workers=workers`` when its signature has that parameter (as
    :func:`simlunar.pipeline.stages.compute_unit` does); other functions simply run
    ``workers`` at a time in threads.
    """

    name = "local"

    def __init__(self, workers: int):
        if workers < 1:
            raise ValueError(f"--workers must be >= 1, got {workers}")
        self.workers = workers

    def describe(self) -> dict:
        return {"executor": self.name, "workers": self.workers}

    def run(self, fn, payloads, *, progress=None):
        if self.workers == 1:
            yield from SerialExecutor().run(fn, payloads, progress=progress)
            return
        kw = {"study_workers": self.workers} if accepts_keyword(fn, "study_workers") else {}
        if len(payloads) <= 1:
            # one unit: its study is still parallel, and its progress can be shown
            if progress is not None:
                kw["progress"] = progress
            for i, p in enumerate(payloads):
                yield i, fn(p, **kw)
            return
        n = min(self.workers, len(payloads))
        with cf.ThreadPoolExecutor(max_workers=n, thread_name_prefix="simlunar-unit") as pool:
            futures = {pool.submit(fn, p, **kw): i for i, p in enumerate(payloads)}
            try:
                for fut in cf.as_completed(futures):
                    yield futures[fut], fut.result()
            except BaseException:
                # units not started yet are dropped; running ones finish in the background
                pool.shutdown(wait=False, cancel_futures=True)
                raise


class DaskExecutor(Executor):
    """Units as tasks on a Dask distributed scheduler (``tcp://host:8786``)."""

    name = "dask"

    def __init__(self, address: str, *, timeout_s: float = 10.0):
        self.address = address
        self.timeout_s = timeout_s

    def describe(self) -> dict:
        return {"executor": self.name, "scheduler": self.address}

    def open(self) -> None:
        """Connect to the scheduler (raises ValueError naming the address if it cannot)."""
        if getattr(self, "_client", None) is not None:
            return
        from distributed import Client

        try:
            self._client = Client(self.address, timeout=self.timeout_s, set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise ValueError(f"--scheduler {self.address}: cannot connect ({exc})") from None

    def run(self, fn, payloads, *, progress=None):
        from distributed import as_completed

        self.open()
        client = self._client
        try:
            run_id = uuid.uuid4().hex[:12]
            futs = client.map(
                fn,
                payloads,
                pure=False,
                key=[f"simlunar-unit-{run_id}-{i}" for i in range(len(payloads))],
            )
            index = {f.key: i for i, f in enumerate(futs)}
            # set_as_default=False keeps the user's own default client untouched, so the
            # loop is passed explicitly
            for fut in as_completed(futs, loop=client.loop):
                yield index[fut.key], fut.result()
        finally:
            self.close()

    def close(self) -> None:
        client = getattr(self, "_client", None)
        self._client = None
        if client is not None:
            client.close()


def make_executor(*, workers: int | None = None, scheduler: str | None = None) -> Executor:
    """The executor for the CLI options ``--workers`` / ``--scheduler``."""
    if scheduler:
        if workers not in (None, 1):
            raise ValueError("give either --workers or --scheduler, not both")
        return DaskExecutor(scheduler)
    return LocalPoolExecutor(workers if workers is not None else default_workers())
