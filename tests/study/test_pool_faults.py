"""A study worker that dies is one clear error wherever the pool notices it."""

from concurrent.futures.process import BrokenProcessPool

import pytest

from simlunar.errors import InfrastructureError
from simlunar.study import protocol


class _DyingPool:
    """Stands in for a ProcessPoolExecutor whose worker is killed after ``alive`` submissions
    (the pool refuses further tasks from then on, as concurrent.futures does)."""

    def __init__(self, alive: int):
        self.alive, self.submitted, self.shut = alive, 0, False
        self._processes = {}

    def submit(self, fn, *args):
        if self.submitted >= self.alive:
            raise BrokenProcessPool("A child process terminated abruptly")
        self.submitted += 1
        return object()

    def shutdown(self, wait=True):
        self.shut = True


def test_a_worker_killed_while_tasks_are_handed_out_is_the_infrastructure_error():
    pool = _DyingPool(alive=1)
    with pytest.raises(InfrastructureError, match="worker process died"):
        protocol._submit_all(pool, [("a", 0), ("b", 0), ("c", 0)])
    assert pool.submitted == 1 and pool.shut


def test_every_task_is_submitted_when_no_worker_dies():
    pool = _DyingPool(alive=3)
    futures = protocol._submit_all(pool, [("a", 0), ("b", 0), ("c", 0)])
    assert len(futures) == 3 and not pool.shut


class _BrokenFuture:
    def result(self):
        raise BrokenProcessPool("A child process terminated abruptly")


def test_a_worker_killed_while_results_are_awaited_is_the_same_error():
    pool = _DyingPool(alive=0)
    with pytest.raises(InfrastructureError, match="worker process died"):
        list(protocol._pool_results(pool, [_BrokenFuture()]))
    assert pool.shut
