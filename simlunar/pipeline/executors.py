"""Executors that run work units: in-process, a local pool, or a Dask cluster.

All three expose one method, :meth:`Executor.run`, that yields ``(index, result)`` as units
finish (in any order); the runner writes each result to the cache as soon as it arrives, in
the parent process, so the cache logic is the same whichever executor computed it.
"""

from __future__ import annotations

import concurrent.futures as cf
import queue
import re
import time
import uuid
from collections.abc import Callable, Iterator
from typing import Any

from simlunar.errors import ConfigError, InfrastructureError

__all__ = [
    "DaskExecutor",
    "Executor",
    "LocalPoolExecutor",
    "SerialExecutor",
    "accepts_keyword",
    "default_workers",
    "make_executor",
    "parse_scheduler_address",
]


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
    turns (a lock in :mod:`simlunar.pipeline.unit`), which costs nothing because a render
    already keeps every core busy. The single-threaded part of a unit, the sampling study,
    runs its (strategy, trial) tasks on ``workers`` forked processes
    (:func:`simlunar.study.sampling.run_sampling_study`), which is where the cores are gained;
    while one unit waits for its study, another renders. Forking is safe here because the
    forked processes only run NumPy/Numba code and never touch Mitsuba's JIT state. A sweep
    with a single unit is parallel too (its study is). Results do not depend on ``workers``.

    ``fn`` gets ``study_workers=workers`` when its signature has that parameter (as
    :func:`simlunar.pipeline.unit.compute_unit` does); other functions simply run
    ``workers`` at a time in threads.
    """

    name = "local"

    def __init__(self, workers: int):
        if workers < 1:
            raise ConfigError(f"--workers must be >= 1, got {workers}")
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
        pool = cf.ThreadPoolExecutor(max_workers=n, thread_name_prefix="simlunar-unit")
        futures = {pool.submit(fn, p, **kw): i for i, p in enumerate(payloads)}
        try:
            for fut in cf.as_completed(futures):
                yield futures[fut], fut.result()
        except BaseException:
            # units not started yet are dropped; running ones finish in the background (not
            # waited for: Ctrl-C must not wait for a render)
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown(wait=True)


_SCHEDULER_ADDRESS = re.compile(
    r"^(?:(?P<scheme>tcp|tls|ws|wss|ucx)://)?(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+)"
    r":(?P<port>\d{1,5})/?$"
)


def parse_scheduler_address(address: str) -> tuple[str, str, int | None]:
    """``(scheme, host, port)`` of a Dask scheduler address, or a ConfigError naming it.

    ``tcp://host:8786``, ``tls://...``, ``ws://...``, ``host:8786`` (tcp) and the in-process
    ``inproc://...`` addresses of a ``LocalCluster(processes=False)`` are accepted.
    """
    a = address.strip()
    if a.startswith("inproc://") and len(a) > len("inproc://"):
        return "inproc", a[len("inproc://") :], None
    m = _SCHEDULER_ADDRESS.match(a)
    port = int(m.group("port")) if m else 0
    if m is None or not 0 < port < 65536:
        raise ConfigError(
            f"--scheduler {address!r}: not a scheduler address (expected tcp://host:port, "
            "e.g. tcp://127.0.0.1:8786)"
        )
    return m.group("scheme") or "tcp", m.group("host").strip("[]"), port


#: largest first message (bytes) a Dask scheduler's TCP handshake may announce
MAX_HANDSHAKE_BYTES = 1 << 24


def _recv_exactly(sock, n: int) -> bytes:
    """Up to ``n`` bytes from ``sock`` (fewer only if the peer closes first)."""
    buf = b""
    while len(buf) < n:
        chunk = sock.recv(n - len(buf))
        if not chunk:
            break
        buf += chunk
    return buf


class DaskExecutor(Executor):
    """Units as tasks on a Dask distributed scheduler (``tcp://host:8786``).

    Faults: a unit whose worker dies is run again on another worker (the scheduler's
    ``allowed-failures``, and ``retries`` resubmissions for an error raised on a worker that
    then goes away); when no worker is connected for ``worker_wait_s`` the run stops with an
    :class:`~simlunar.errors.InfrastructureError` instead of waiting forever, and so does a
    lost scheduler. Finished units are written by the runner as they arrive, so they are kept.
    """

    name = "dask"

    def __init__(
        self,
        address: str,
        *,
        timeout_s: float = 10.0,
        retries: int = 2,
        worker_wait_s: float = 60.0,
        poll_s: float = 1.0,
    ):
        self.scheme, self.host, self.port = parse_scheduler_address(address)
        self.address = address.strip()
        self.timeout_s = timeout_s
        self.retries = retries
        self.worker_wait_s = worker_wait_s
        self.poll_s = poll_s
        self._client = None

    def describe(self) -> dict:
        return {"executor": self.name, "scheduler": self.address}

    def _probe(self) -> None:
        """A plain TCP connection first: a closed port fails at once, without Dask's retries."""
        import socket

        if self.scheme not in ("tcp", "tls", "ws", "wss"):
            return
        try:
            with socket.create_connection((self.host, self.port), timeout=self.timeout_s) as s:
                if self.scheme == "tcp":
                    # a Dask server sends its handshake as soon as it accepts; another
                    # server (HTTP, ...) waits for the client, and Dask's Client would wait
                    # for it forever
                    try:
                        head = _recv_exactly(s, 8)
                    except TimeoutError:
                        raise ConfigError(
                            f"--scheduler {self.address}: something listens there but it "
                            f"does not answer like a Dask scheduler within {self.timeout_s:g} s"
                        ) from None
                    # Dask's TCP comm frames every message with its length as a little-endian
                    # uint64 first; a handshake is a few hundred bytes. Other servers (HTTP
                    # banners, garbage) give a length no handshake has, and Dask's Client
                    # would wait on them until its own timeout, then fail with a traceback
                    size = int.from_bytes(head, "little") if len(head) == 8 else 0
                    if not 0 < size <= MAX_HANDSHAKE_BYTES:
                        raise ConfigError(
                            f"--scheduler {self.address}: something listens there but it "
                            "does not speak Dask's protocol (not a Dask scheduler)"
                        )
        except OSError as exc:
            why = (
                f"no answer within {self.timeout_s:g} s"
                if isinstance(exc, TimeoutError)
                else (exc.strerror or str(exc))
            )
            raise ConfigError(f"--scheduler {self.address}: cannot connect ({why})") from None

    def open(self) -> None:
        """Connect to the scheduler (raises ConfigError naming the address if it cannot)."""
        if getattr(self, "_client", None) is not None:
            return
        self._probe()
        from distributed import Client

        try:
            self._client = Client(self.address, timeout=self.timeout_s, set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise ConfigError(
                f"--scheduler {self.address}: cannot connect ({' '.join(str(exc).split())})"
            ) from None

    def _lost(self, what: str) -> InfrastructureError:
        return InfrastructureError(f"--scheduler {self.address}: {what}")

    def _check_workers(self, client, idle_since: float | None) -> float | None:
        """Raise when the scheduler is gone or has had no worker for ``worker_wait_s``."""
        if client.status not in ("running", "connecting"):
            raise self._lost("lost the connection to the scheduler")
        try:
            n = len(client.nthreads())
        except Exception as exc:  # any failure to reach it: the scheduler is gone
            raise self._lost(
                f"lost the connection to the scheduler ({type(exc).__name__})"
            ) from None
        now = time.monotonic()
        if n > 0:
            return None
        if idle_since is None:
            return now
        if now - idle_since > self.worker_wait_s:
            raise self._lost(
                f"no worker connected for {self.worker_wait_s:g} s (the last one was lost); "
                "start workers"
            )
        return idle_since

    def run(self, fn, payloads, *, progress=None):
        from concurrent.futures import CancelledError

        try:
            from distributed import KilledWorker
        except ImportError:  # pragma: no cover - older distributed
            from distributed.scheduler import KilledWorker

        self.open()
        client = self._client
        try:
            run_id = uuid.uuid4().hex[:12]
            futs = client.map(
                fn,
                payloads,
                pure=False,
                retries=self.retries,
                key=[f"simlunar-unit-{run_id}-{i}" for i in range(len(payloads))],
            )
            index = {f.key: i for i, f in enumerate(futs)}
            finished: queue.Queue = queue.Queue()
            for f in futs:
                f.add_done_callback(finished.put)  # called from another thread, any outcome
            n = len(futs)
            del futs  # released one by one as their results arrive
            idle_since = None
            for _ in range(n):
                while True:
                    try:
                        f = finished.get(timeout=self.poll_s)
                        break
                    except queue.Empty:
                        idle_since = self._check_workers(client, idle_since)
                try:
                    result = f.result()
                except KilledWorker:
                    raise self._lost(
                        f"unit {index[f.key]}: every worker that ran it died (KilledWorker)"
                    ) from None
                except (CancelledError, OSError) as exc:
                    raise self._lost(
                        f"lost the connection to the scheduler ({type(exc).__name__})"
                    ) from None
                i = index[f.key]
                f.release()  # the parent keeps the result: the cluster need not (nor recompute it)
                yield i, result
        finally:
            self.close()

    def close(self) -> None:
        client = getattr(self, "_client", None)
        self._client = None
        if client is not None:
            try:
                client.close(timeout=self.timeout_s)
            except Exception:  # closing a client whose scheduler is gone may fail; nothing to keep
                pass


def make_executor(*, workers: int | None = None, scheduler: str | None = None) -> Executor:
    """The executor for the CLI options ``--workers`` / ``--scheduler``."""
    if scheduler:
        if workers not in (None, 1):
            raise ConfigError("give either --workers or --scheduler, not both")
        return DaskExecutor(scheduler)
    return LocalPoolExecutor(workers if workers is not None else default_workers())
