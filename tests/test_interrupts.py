"""Ctrl-C (SIGINT) through the flag of :mod:`simlunar.interrupts`: raised at once, or held to the
end of a deferred region; the flag survives code that swallows the exception."""

from __future__ import annotations

import signal
import threading

import pytest

from simlunar import interrupts


@pytest.fixture
def sigint():
    """Restore pytest's SIGINT handler and a clear flag around each test."""
    before = signal.getsignal(signal.SIGINT)
    interrupts.clear()
    yield
    signal.signal(signal.SIGINT, before)
    interrupts.clear()


def _ctrl_c():
    signal.raise_signal(signal.SIGINT)


def test_install_routes_sigint_through_the_flag(sigint):
    assert not interrupts.installed()
    interrupts.install()
    assert interrupts.installed()
    assert not interrupts.interrupted()
    with pytest.raises(KeyboardInterrupt):
        _ctrl_c()
    assert interrupts.interrupted()
    interrupts.clear()
    assert not interrupts.interrupted()


def test_the_flag_outlives_a_swallowed_keyboard_interrupt(sigint):
    interrupts.install()
    try:
        _ctrl_c()
    except KeyboardInterrupt:
        pass  # e.g. Dr.Jit turning it into another error while it initialises
    assert interrupts.interrupted()


def test_deferred_holds_the_interrupt_to_the_end_of_the_region(sigint):
    interrupts.install()
    reached = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts.deferred():
            _ctrl_c()
            assert interrupts.interrupted()  # recorded at once
            reached.append("after the signal")
    assert reached == ["after the signal"]
    assert interrupts.interrupted()


def test_deferred_without_an_interrupt_raises_nothing(sigint):
    interrupts.install()
    with interrupts.deferred():
        x = 1
    assert x == 1 and not interrupts.interrupted()
    # and the region ended: a later Ctrl-C raises at once again
    reached = []
    with pytest.raises(KeyboardInterrupt):
        _ctrl_c()
        reached.append("never")
    assert reached == []


def test_deferred_is_a_plain_block_where_install_did_not_route_sigint(sigint):
    signal.signal(signal.SIGINT, signal.default_int_handler)
    reached = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts.deferred():
            _ctrl_c()
            reached.append("never")
    assert reached == []
    assert not interrupts.interrupted()  # Python's own handler sets no flag


def test_install_off_the_main_thread_changes_nothing(sigint):
    before = signal.getsignal(signal.SIGINT)
    t = threading.Thread(target=interrupts.install)
    t.start()
    t.join()
    assert signal.getsignal(signal.SIGINT) is before


def test_deferred_off_the_main_thread_just_runs_the_block(sigint):
    interrupts.install()
    seen = []

    def work():
        with interrupts.deferred():
            seen.append(interrupts._DEFERRING.is_set())

    t = threading.Thread(target=work)
    t.start()
    t.join()
    assert seen == [False]


def test_a_real_ctrl_c_inside_a_study_keeps_its_finished_steps(sigint, monkeypatch):
    """SIGINT through the flag while the second strategy of a sampling study computes: the
    first strategy is kept, the rerun computes only the others and gives the same rows."""
    import numpy as np

    from simlunar.study import protocol
    from simlunar.study.sampling import SamplingStudyOptions, run_sampling_study
    from simlunar.study.steps import MemorySteps

    rng = np.random.default_rng(0)
    depth = np.cumsum(np.cumsum(rng.normal(size=(32, 32)), 0), 1)
    image = rng.random((32, 32)).astype(np.float32)
    opts = SamplingStudyOptions(
        strategies=("random", "grid"), densities=(1 / 8,), trials=2, metrics=("mse",)
    )
    clean = run_sampling_study(depth, image, opts, rng=1)
    real = protocol._task_outcomes
    computed = []

    def task(state, label, trial):
        if label == "grid" and not computed.count("resumed"):
            _ctrl_c()
        computed.append(label)
        return real(state, label, trial)

    monkeypatch.setattr(protocol, "_task_outcomes", task)
    interrupts.install()
    steps = MemorySteps()
    with pytest.raises(KeyboardInterrupt):
        run_sampling_study(depth, image, opts, rng=1, steps=steps)
    assert interrupts.interrupted() and list(steps.saved) == ["sampling strategy random"]
    computed[:] = ["resumed"]
    resumed = run_sampling_study(depth, image, opts, rng=1, steps=steps)
    assert computed == ["resumed", "grid", "grid"]
    assert resumed.rows == clean.rows
