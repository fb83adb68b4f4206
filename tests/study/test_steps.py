"""Checkpoints inside a study: a study cut short by Ctrl-C at its second sub-step and resumed
from the kept steps computes only the missing steps and gives exactly the result of an
uninterrupted study (shared random streams restored); its progress counts to its total."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from simlunar.progress import reporting
from simlunar.sensors.base import Acquisition
from simlunar.study import protocol, sampling
from simlunar.study.sampling import SamplingStudyOptions, run_sampling_study
from simlunar.study.steps import MemorySteps, ProtocolSteps, resumable


def _draws(steps, names, stream, *, stop_at=None, computed=None):
    """Steps that each draw from one shared stream (as the scanner's frames draw noise)."""
    out = []
    for i, name in enumerate(names):

        def compute(name=name, i=i):
            if i == stop_at:
                raise KeyboardInterrupt
            computed.append(name)
            return stream.normal(size=3)

        value, _ = resumable(steps, name, compute, streams=(stream,))
        out.append(value)
    return np.concatenate(out)


def test_resumed_steps_draw_what_an_uninterrupted_run_draws():
    names = ["a", "b", "c", "d"]
    clean = _draws(None, names, np.random.default_rng(7), computed=[])
    steps, first = MemorySteps(), []
    with pytest.raises(KeyboardInterrupt):
        _draws(steps, names, np.random.default_rng(7), stop_at=1, computed=first)
    assert first == ["a"] and set(steps.saved) == {"a"}
    again: list = []
    resumed = _draws(steps, names, np.random.default_rng(7), computed=again)
    assert again == ["b", "c", "d"] and steps.loads == ["a"]
    np.testing.assert_array_equal(resumed, clean)
    # without the stream state the later steps would draw other numbers: the test can fail
    lost = np.random.default_rng(7)
    assert not np.array_equal(np.r_[clean[:3], lost.normal(size=9)], clean)


def test_a_step_of_another_shape_is_computed_again():
    steps = MemorySteps()
    steps.save("x", {"value": 1, "streams": [{"bit_generator": "PCG64"}] * 2})  # two streams
    value, loaded = resumable(steps, "x", lambda: 5, streams=(np.random.default_rng(0),))
    assert (value, loaded) == (5, False)
    assert resumable(steps, "x", lambda: 6, streams=(np.random.default_rng(0),)) == (5, True)


@pytest.fixture(scope="module")
def scene():
    rng = np.random.default_rng(3)
    depth = ndimage.gaussian_filter(rng.normal(size=(48, 48)), 3) * 5 + 20
    gy, gx = np.gradient(depth)
    image = (1 / np.sqrt(1 + gx**2 + gy**2)).astype(np.float32)
    return depth, image


OPTS = SamplingStudyOptions(
    strategies=("random", "grid", "wavelet"),
    densities=(1 / 8, 1 / 32),
    trials=3,
    metrics=("mse", "grad"),
)


@pytest.mark.parametrize("workers", [1, 2])
def test_a_sampling_study_interrupted_at_its_second_strategy_resumes_exactly(
    scene, monkeypatch, workers
):
    depth, image = scene
    clean = run_sampling_study(depth, image, OPTS, rng=11, workers=workers)
    real = protocol._task_outcomes
    calls: list = []

    def counted(state, label, trial):
        calls.append(label)
        if stop[0] and label == "grid":  # Ctrl-C at the second strategy's first trial
            raise KeyboardInterrupt
        return real(state, label, trial)

    monkeypatch.setattr(protocol, "_task_outcomes", counted)
    stop = [True]
    steps = MemorySteps()
    with pytest.raises(KeyboardInterrupt):
        run_sampling_study(depth, image, OPTS, rng=11, workers=1, steps=steps)
    assert set(steps.saved) == {"sampling strategy random"}
    stop[0], calls[:] = False, []
    events: list = []
    with reporting(events.append):
        resumed = run_sampling_study(depth, image, OPTS, rng=11, workers=1, steps=steps)
    # only the missing strategies were computed, every trial of each once
    assert sorted(calls) == sorted(["grid"] * 3 + ["wavelet"] * 3)
    assert steps.loads == ["sampling strategy random"]
    assert resumed.rows == clean.rows
    assert resumed.scores == clean.scores
    # the progress starts at the restored acquisitions and ends at its total
    study = [e for e in events if e.stage == "sampling study"]
    assert (study[0].done, study[0].total, study[0].unit) == (6, 18, "acquisitions")
    assert study[-1].finished and study[-1].done == study[-1].total == 18
    # and a study whose every strategy is kept computes nothing
    calls[:] = []
    again = run_sampling_study(depth, image, OPTS, rng=11, workers=1, steps=steps)
    assert calls == [] and again.rows == clean.rows


def test_kept_steps_of_a_parallel_study_arrive_before_it_ends(scene, monkeypatch):
    """With forked workers, each strategy is kept as soon as its trials are back (not all at
    the end): a Ctrl-C in the parent after the first strategy keeps it."""
    depth, image = scene
    steps = MemorySteps()
    saved = steps.save

    def save_then_stop(name, value):
        saved(name, value)
        raise KeyboardInterrupt

    monkeypatch.setattr(steps, "save", save_then_stop)
    with pytest.raises(KeyboardInterrupt):
        sampling.run_sampling_study(depth, image, OPTS, rng=11, workers=2, steps=steps)
    assert list(steps.saved) == ["sampling strategy random"]


# ------------------------------------------------------------- the protocol wrapper itself
def _fake_run(log: list, stream: np.random.Generator, *, stop_at=None):
    """A protocol over labels x 2 trials x 2 budgets whose scores draw from one shared stream
    (as the scanner's frames draw their noise); logs each task it runs."""

    def run(trials: protocol.Trials):
        for label in trials.planners:
            for t in range(trials.trials):
                if (label, t) == stop_at:
                    raise KeyboardInterrupt
                log.append((label, t))
                yield [
                    protocol.Outcome(label, t, b, k, Acquisition(np.zeros((k, 2)), np.zeros(k),
                                     (4, 4), frames=k), {"mse": float(stream.normal())})
                    for b, k in enumerate(trials.ks)
                ]  # fmt: skip

    return run


def _rows(oc):
    return protocol.outcome_rows(oc, {"label": oc.label}, {"k": oc.k})


def _wrapped(steps, log, stream, *, stop_at=None, advance=None):
    trials = protocol.Trials(dict.fromkeys("abc"), [3, 5], 2, lambda *a: (None, None))
    store = ProtocolSteps(steps, {lb: f"step {lb}" for lb in "abc"}, streams=(stream,))
    run = _fake_run(log, stream, stop_at=stop_at)
    return list(store.run(trials, run, rows=_rows, advance=advance))


def test_the_wrapper_keeps_each_label_and_resumes_it_exactly():
    clean = _wrapped(None, [], np.random.default_rng(5))
    assert [s.label for s in clean] == ["a", "b", "c"] and not any(s.loaded for s in clean)
    # rows: one per (reconstruction, metric) of each outcome, trial by trial, budget by budget
    assert [(r["label"], r["trial"], r["k"]) for r in clean[0].rows] == [
        ("a", 0, 3), ("a", 0, 5), ("a", 1, 3), ("a", 1, 5)
    ]  # fmt: skip
    assert set(clean[0].rows[0]) == {"label", "reconstruction", "k", "trial", "metric", "value"}
    # what is kept of an outcome: scores and cost, no samples
    assert all(len(oc.acquisition.values) == 0 for oc in clean[0].outcomes)
    assert [oc.acquisition.frames for oc in clean[0].outcomes] == [3, 5, 3, 5]

    steps, log = MemorySteps(), []
    with pytest.raises(KeyboardInterrupt):  # Ctrl-C at b's second trial
        _wrapped(steps, log, np.random.default_rng(5), stop_at=("b", 1))
    assert list(steps.saved) == ["step a"]
    log, acquisitions = [], []
    resumed = _wrapped(steps, log, np.random.default_rng(5), advance=acquisitions.append)
    assert log == [("b", 0), ("b", 1), ("c", 0), ("c", 1)] and steps.loads == ["step a"]
    assert [s.loaded for s in resumed] == [True, False, False]
    assert acquisitions == [2, 2, 2, 2]  # the tasks run, not the loaded label
    # the stream is restored after the kept label: b and c draw what they drew uninterrupted
    assert [s.rows for s in resumed] == [s.rows for s in clean]
    lost = np.random.default_rng(5)
    assert [r["value"] for r in clean[1].rows] != list(lost.normal(size=4))


def test_a_kept_step_of_another_shape_is_run_again():
    # a step an older run kept under the same name in another form (a list of trials, no
    # stream states) is not misread: the label is run again
    steps, log = MemorySteps(), []
    steps.save("step a", [[("a", 0)]])
    steps.save("step b", {"value": [("b", 0, [], None)], "streams": [None]})
    got = _wrapped(steps, log, np.random.default_rng(5))
    assert [s.loaded for s in got] == [False, False, False]
    assert log == [(lb, t) for lb in "abc" for t in range(2)]
    assert _wrapped(steps, [], np.random.default_rng(5))[0].loaded
