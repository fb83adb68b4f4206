"""Executors that run work units: in-process, a local process pool, or a Dask cluster.

All three expose one method, :meth:`Executor.run`, that yields ``(index, result)`` as units
finish (in any order); the runner writes each result to the cache as soon as it arrives, in
the parent process, so the cache logic is the same whichever executor computed it.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import multiprocessing as mp
import os
import uuid
from collections.abc import Callable, Iterator
from typing import Any


def default_workers() -> int:
    """Worker count when none is given: 1 (rendering already uses every core)."""
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


def _worker_init(threads: int) -> None:
    # each worker gets its share of the cores: renders in N workers each using every core
    # would oversubscribe the machine and make the pool slower than one process
    for var in (
        "OMP_NUM_THREADS",
        "OPENBLAS_NUM_THREADS",
        "MKL_NUM_THREADS",
        "NUMBA_NUM_THREADS",
        "SIMLUNAR_RENDER_THREADS",  # Dr.Jit's render thread pool (simlunar.render.backend)
    ):
        os.environ[var] = str(threads)


@contextlib.contextmanager
def _parent_render_threads(threads: int):
    """The parent works as one of the pool's workers: give its renders their share of cores."""
    from simlunar.render import backend

    old = backend.set_render_threads(threads) if backend.is_initialised() else None
    try:
        yield
    finally:
        if old is not None:
            backend.set_render_threads(old)


class LocalPoolExecutor(Executor):
    """``workers`` local workers: this process plus ``workers - 1`` spawned processes.

    The parent process works too (in a thread), because it has already paid for importing
    Mitsuba and warming its kernels; each spawned process pays that once (about 2 s), which
    is what limits the speed-up on short units. Processes are spawned, not forked: Mitsuba's
    JIT state does not survive ``fork``. Units are handed out in order as workers free up.
    """

    name = "local"

    def __init__(self, workers: int):
        if workers < 1:
            raise ValueError(f"--workers must be >= 1, got {workers}")
        self.workers = workers

    def describe(self) -> dict:
        return {"executor": self.name, "workers": self.workers}

    def run(self, fn, payloads, *, progress=None):
        if self.workers == 1 or len(payloads) <= 1:
            yield from SerialExecutor().run(fn, payloads, progress=progress)
            return
        n = min(self.workers, len(payloads))
        threads = max(1, (os.cpu_count() or 1) // n)
        with _parent_render_threads(threads):
            yield from self._run_pool(fn, payloads, n, threads)

    def _run_pool(self, fn, payloads, n, threads):
        ctx = mp.get_context("spawn")
        pending = list(range(len(payloads)))
        running: dict[cf.Future, tuple[int, cf.Executor]] = {}
        with (
            cf.ThreadPoolExecutor(max_workers=1) as local,
            cf.ProcessPoolExecutor(
                max_workers=n - 1, mp_context=ctx, initializer=_worker_init, initargs=(threads,)
            ) as pool,
        ):

            def submit(ex: cf.Executor) -> None:
                i = pending.pop(0)
                running[ex.submit(fn, payloads[i])] = (i, ex)

            submit(local)
            for _ in range(n - 1):
                if pending:
                    submit(pool)
            try:
                while running:
                    done, _ = cf.wait(running, return_when=cf.FIRST_COMPLETED)
                    for fut in sorted(done, key=lambda f: running[f][0]):
                        i, ex = running.pop(fut)
                        if pending:
                            submit(ex)
                        yield i, fut.result()
            except BaseException:
                for fut in running:
                    fut.cancel()
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
