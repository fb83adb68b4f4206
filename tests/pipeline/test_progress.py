"""Progress of a run where stderr is not a terminal: plain lines, not a live bar that prints
nothing until the run ends (a run logged with ``2> run.log`` showed no progress at all)."""

from __future__ import annotations

import io
import re
import sys

from simlunar.pipeline import progress


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
        bar.stage("sampling", done, 10)
    stages = [ln for ln in out.getvalue().splitlines() if "sampling" in ln]
    assert stages == ["t: unit 1/2: sampling 3/10", "t: unit 1/2: sampling 5/10"]


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
