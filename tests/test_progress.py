"""The progress channel: stages nest, count to their totals and close; a listener sees every
change; without one nothing is sent; a forked child never reports; each thread has its own."""

from __future__ import annotations

import threading

import pytest

from simlunar import progress
from simlunar.progress import Event, advance, reporting, stage


def _record():
    events: list[Event] = []
    return events, events.append


def test_a_listener_sees_nested_stages_count_to_their_totals():
    events, listen = _record()
    with reporting(listen):
        with stage("scanner study", total=2, unit="steps") as study:
            with stage("gray_code scan", total=3, unit="frames"):
                for _ in range(3):
                    advance(unit="frames")  # what the capture does per sensed frame
            study.advance()
            with stage("dot frames", total=2, unit="frames") as dots:
                dots.advance(2)
            study.advance()
    texts = [(e.path, e.text(), e.finished) for e in events]
    study, scan, dots = (
        ("scanner study",),
        ("scanner study", "gray_code scan"),
        (
            "scanner study",
            "dot frames",
        ),
    )
    assert texts == [
        (study, "scanner study 0/2 steps", False),
        (scan, "gray_code scan 0/3 frames", False),
        (scan, "gray_code scan 1/3 frames", False),
        (scan, "gray_code scan 2/3 frames", False),
        (scan, "gray_code scan 3/3 frames", False),
        (scan, "gray_code scan 3/3 frames", True),
        (study, "scanner study 1/2 steps", False),
        (dots, "dot frames 0/2 frames", False),
        (dots, "dot frames 2/2 frames", False),
        (dots, "dot frames 2/2 frames", True),
        (study, "scanner study 2/2 steps", False),
        (study, "scanner study 2/2 steps", True),
    ]
    # every stage closes once, at its total
    closed = [e for e in events if e.finished]
    assert [e.depth for e in closed] == [1, 1, 0]
    assert all(e.done == e.total for e in closed)


def test_advance_counts_only_into_a_stage_of_its_unit_and_only_when_one_is_open():
    events, listen = _record()
    with reporting(listen):
        advance(unit="frames")  # no stage open: nothing
        with stage("lidar study", total=4, unit="acquisitions"):
            advance(3, unit="frames")  # a frame is not an acquisition
            advance(2)  # no unit given: the innermost stage
    assert [e.done for e in events] == [0, 2, 2]


def test_a_stage_can_start_with_restored_items_and_learn_its_total():
    events, listen = _record()
    with reporting(listen):
        with stage("sampling study", total=30, unit="acquisitions", done=20) as s:
            s.update(25)
        with stage("beams", unit="beams") as b:
            b.update(5, total=8)
    assert [(e.done, e.total) for e in events] == [(20, 30), (25, 30), (25, 30), (0, None),
                                                   (5, 8), (5, 8)]  # fmt: skip
    assert events[3].text() == "beams 0 beams"


def test_without_a_listener_stages_still_count_and_nothing_is_sent():
    with stage("x", total=2) as s:
        s.advance()
        advance()  # no listener: no stage is tracked, nothing to advance
    assert s.done == 1
    events, listen = _record()
    with reporting(listen), reporting(None):  # None silences an outer listener
        with stage("y", total=1) as t:
            t.advance()
    assert events == []


def test_an_exception_closes_the_stage_early_and_is_not_swallowed():
    events, listen = _record()
    with reporting(listen), pytest.raises(KeyboardInterrupt):
        with stage("scan", total=5, unit="frames") as s:
            s.advance()
            raise KeyboardInterrupt
    assert events[-1].finished and (events[-1].done, events[-1].total) == (1, 5)
    # and the next stage is outermost again (the interrupted one left the stack)
    with reporting(listen):
        with stage("next"):
            pass
    assert events[-1].path == ("next",)


def test_a_forked_child_never_reports_to_the_parents_listener(monkeypatch):
    events, listen = _record()
    with reporting(listen):
        real = progress.os.getpid()
        monkeypatch.setattr(progress.os, "getpid", lambda: real + 1)  # as in a fork
        with stage("in the child", total=1) as s:
            s.advance()
        monkeypatch.undo()
        with stage("in the parent", total=1):
            pass
    assert {e.stage for e in events} == {"in the parent"}


def test_each_thread_has_its_own_listener():
    main_events, listen = _record()
    other: list[Event] = []

    def unit():
        with reporting(other.append), stage("thread unit", total=1) as s:
            s.advance()

    with reporting(listen):
        t = threading.Thread(target=unit)
        t.start()
        t.join()
        with stage("main unit", total=1):
            pass
    assert {e.stage for e in main_events} == {"main unit"}
    assert {e.stage for e in other} == {"thread unit"}
