"""Progress of a run where stderr is not a terminal: plain lines, not a live bar that prints
nothing until the run ends (a run logged with ``2> run.log`` showed no progress at all)."""

from __future__ import annotations

import io
import re
import sys

from simlunar.pipeline import progress
from simlunar.progress import Event


def test_lines_report_each_unit_with_elapsed_and_eta(monkeypatch):
    clock = iter([0.0, 10.0, 10.0, 30.0, 30.0])
    monkeypatch.setattr(progress.time, "monotonic", lambda: next(clock))
    out = io.StringIO()
    bar = progress._Lines(3, 1, "t2", stream=out)
    bar.advance()  # 10 s for the first computed unit: one left, ETA 10 s
    bar.advance()
    bar.stop()
    lines = out.getvalue().splitlines()
    assert lines == [
        "t2: 1/3 units (1 cached)",
        "t2: 2/3 units, 0:00:10 elapsed, ETA 0:00:10",
        "t2: 3/3 units, 0:00:30 elapsed",
    ]


def test_lines_show_the_stage_at_most_once_per_interval(monkeypatch):
    now = [0.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: now[0])
    out = io.StringIO()
    bar = progress._Lines(2, 0, "t", stream=out, every_s=60.0)
    for t, done in [(10.0, 1), (59.0, 2), (61.0, 3), (100.0, 4), (122.0, 5)]:
        now[0] = t
        bar.event(Event(("sampling study",), done, 10, "acquisitions"))
    stages = [ln for ln in out.getvalue().splitlines() if "sampling" in ln]
    assert stages == [
        # 3/10 of a unit in 61 s: 142 s for the rest of it and 203 s for the second unit
        "t: unit 1/2: sampling study 3/10 acquisitions, unit 30 %, ETA 0:05:46",
        "t: unit 1/2: sampling study 5/10 acquisitions, unit 50 %, ETA 0:06:06",
    ]


def test_lines_name_every_open_stage_with_its_total_and_drop_closed_ones(monkeypatch):
    now = [0.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: now[0])
    out = io.StringIO()
    bar = progress._Lines(1, 0, "dlp", stream=out, every_s=30.0)
    study = ("scanner study",)
    scan = (*study, "gray_code scan")
    for t, ev in [
        (1.0, Event(study, 0, 3, "steps")),
        (2.0, Event(scan, 0, 22, "frames")),
        (31.0, Event(scan, 11, 22, "frames")),  # 30 s after the start: shown
        (40.0, Event(scan, 22, 22, "frames", finished=True)),
        (41.0, Event(study, 1, 3, "steps")),
        (62.0, Event(study, 2, 3, "steps")),  # shown, without the closed scan
    ]:
        now[0] = t
        bar.event(ev)
    bar.advance()
    assert out.getvalue().splitlines() == [
        "dlp: 0/1 units (0 cached)",
        # half of the first of three steps: 1/6 of the unit in 31 s, 155 s left
        "dlp: unit 1/1: scanner study 0/3 steps > gray_code scan 11/22 frames, unit 17 %, ETA 0:02:35",
        "dlp: unit 1/1: scanner study 2/3 steps, unit 67 %, ETA 0:00:31",
        "dlp: 1/1 units, 0:01:02 elapsed",
    ]


def test_the_older_three_argument_stage_still_shows(monkeypatch):
    now = [100.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: now[0])
    out = io.StringIO()
    bar = progress._Lines(1, 0, "t", stream=out, every_s=1.0)
    now[0] = 102.0
    bar.stage("study", 2, 3)
    assert out.getvalue().splitlines()[-1] == "t: unit 1/1: study 2/3 steps, unit 67 %, ETA 0:00:01"


def test_the_bar_shows_each_stage_under_the_units_and_removes_it_when_closed(monkeypatch):
    class Tty(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr(sys, "stderr", Tty())
    bar = progress._progress(True, 1, 0, "t")
    try:
        study = ("sampling study",)
        bar.event(Event(study, 0, 250, "acquisitions"))
        bar.event(Event((*study, "inner"), 1, None, "frames"))
        tasks = {t.description: t for t in bar.p.tasks}
        assert tasks["[bold]t[/]"].fields["unit"] == "units"
        # the study counts its acquisitions, not units
        inner = tasks["  sampling study"]
        assert (inner.total, inner.fields["unit"]) == (250, "acquisitions")
        assert tasks["    inner"].total is None
        bar.event(Event(study, 40, 250, "acquisitions"))
        assert bar.p.tasks[1].completed == 40
        # the units bar moves inside the one unit (it stayed at 0/1 with no ETA)
        assert bar.p.tasks[0].completed == 40 / 250
        bar.event(Event(study, 250, 250, "acquisitions", finished=True))
        assert [t.description for t in bar.p.tasks] == ["[bold]t[/]"]  # nested one gone too
        bar.event(Event(("guide render",), 0, 1, "frames"))
        bar.advance()
        assert [t.description for t in bar.p.tasks] == ["[bold]t[/]"]
        assert bar.p.tasks[0].completed == 1
    finally:
        bar.stop()


def test_a_run_logged_to_a_file_gets_lines_and_a_terminal_gets_the_bar(monkeypatch):
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    bar = progress._progress(True, 2, 0, "t")
    assert isinstance(bar, progress._Lines)
    assert re.match(r"^t: 0/2 units \(0 cached\)$", sys.stderr.getvalue().strip())
    assert progress._progress(False, 2, 0, "t") is None

    class Tty(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr(sys, "stderr", Tty())
    bar = progress._progress(True, 2, 0, "t")
    try:
        assert isinstance(bar, progress._Bar)
    finally:
        bar.stop()


def test_the_unit_fraction_nests_inner_stages_into_one_item_of_the_outer_one():
    study = ("study",)
    scan = (*study, "scan")
    assert progress.unit_fraction([]) == 0.0
    assert progress.unit_fraction([Event(study, 1, 4, "steps")]) == 0.25
    # one of four steps done and half of the second: (1 + 11/22) / 4
    got = progress.unit_fraction([Event(scan, 11, 22, "frames"), Event(study, 1, 4, "steps")])
    assert got == 0.375
    # a stage with no total adds nothing; a count past its total is capped at 1
    assert progress.unit_fraction([Event(study, 2, 4, "steps"), Event(scan, 5, None, "f")]) == 0.5
    assert progress.unit_fraction([Event(study, 9, 4, "steps")]) == 1.0
