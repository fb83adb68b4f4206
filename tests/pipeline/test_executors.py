"""LocalPoolExecutor: units in threads, at most ``workers`` at a time, study workers passed on."""

from __future__ import annotations

import threading
import time

import pytest

from simlunar.pipeline.executors import LocalPoolExecutor, SerialExecutor


class _Probe:
    """A unit function that records how many calls overlap and what it was given."""

    def __init__(self):
        self.lock = threading.Lock()
        self.active = 0
        self.peak = 0
        self.kwargs = []

    def __call__(self, payload, *, study_workers=1, progress=None):
        with self.lock:
            self.active += 1
            self.peak = max(self.peak, self.active)
            self.kwargs.append({"study_workers": study_workers, "progress": progress})
        time.sleep(0.05)
        with self.lock:
            self.active -= 1
        return payload * 10


def test_pool_runs_workers_units_at_a_time_and_passes_study_workers():
    probe = _Probe()
    out = dict(LocalPoolExecutor(2).run(probe, list(range(6))))
    assert out == {i: i * 10 for i in range(6)}
    assert probe.peak == 2
    assert all(k["study_workers"] == 2 and k["progress"] is None for k in probe.kwargs)


def test_single_unit_keeps_parallel_study_and_progress():
    probe = _Probe()

    def hook(stage, done, total):
        pass

    assert list(LocalPoolExecutor(3).run(probe, [4], progress=hook)) == [(0, 40)]
    assert probe.kwargs == [{"study_workers": 3, "progress": hook}]


def test_functions_without_study_workers_still_run():
    assert dict(LocalPoolExecutor(2).run(lambda p: p + 1, [1, 2, 3])) == {0: 2, 1: 3, 2: 4}


def test_one_worker_is_serial_in_order():
    probe = _Probe()
    assert list(LocalPoolExecutor(1).run(probe, [1, 2])) == list(
        SerialExecutor().run(probe, [1, 2])
    )
    assert probe.peak == 1 and probe.kwargs[0]["study_workers"] == 1


def test_a_failing_unit_propagates():
    def boom(p):
        if p == 1:
            raise RuntimeError("unit 1 failed")
        return p

    with pytest.raises(RuntimeError, match="unit 1 failed"):
        list(LocalPoolExecutor(2).run(boom, [0, 1, 2, 3]))


def test_bad_worker_count():
    with pytest.raises(ValueError, match="--workers must be >= 1"):
        LocalPoolExecutor(0)
