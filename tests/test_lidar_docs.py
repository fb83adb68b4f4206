"""The examples of docs/lidar.md run as written and print what the text says they print."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCKS = re.findall(
    r"^```python(?: runnable)?\n(.*?)^```", (ROOT / "docs" / "lidar.md").read_text(), re.S | re.M
)


def _run(code: str) -> str:
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                       timeout=600)  # fmt: skip
    assert r.returncode == 0, r.stderr[-3000:]
    return r.stdout


def test_the_docs_show_two_examples_with_their_output():
    assert len(BLOCKS) == 2
    for block in BLOCKS:
        assert "long run" not in block.splitlines()[0]
        # each block ends with a comment giving the output it prints
        assert block.strip().splitlines()[-1].startswith("# ")


def test_array_example_reads_the_sub_bin_range():
    out = _run(BLOCKS[0])
    m = re.search(r"range ([\d.]+) m, error ([+-][\d.]+) mm, bound ([\d.]+) mm", out)
    assert m, out
    r, err, bound = (float(x) for x in m.groups())
    assert abs(r - 50.0123) < 3 * bound * 1e-3
    assert err == pytest.approx(1e3 * (r - 50.0123), abs=0.06)
    assert bound == pytest.approx(4.8, abs=0.1)
    # the printed line is the one the docs show
    assert out.strip() == BLOCKS[0].strip().splitlines()[-1].removeprefix("# ")


@pytest.mark.render
@pytest.mark.slow
def test_steered_beam_example_measures_every_beam_on_the_terrain():
    out = _run(BLOCKS[1])
    m = re.search(r"valid ([\d.]+), heights ([+-][\d.]+) \.\.\. ([+-][\d.]+) m, ([\d.]+) s", out)
    assert m, out
    valid, lo, hi, seconds = (float(x) for x in m.groups())
    assert valid == 1.0 and -1.5 < lo < hi < 1.5 and seconds > 0
    # the numbers the docs show, up to the render's variant (llvm / cuda sample differently)
    shown = re.findall(r"[+-]?\d+\.\d+", BLOCKS[1].strip().splitlines()[-1])
    assert [float(x) for x in shown] == pytest.approx([valid, lo, hi, seconds], abs=0.05)
