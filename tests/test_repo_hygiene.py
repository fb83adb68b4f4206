"""The repository speaks of itself only: no tracker numbers, no paths outside it.

Every git-tracked text file (``git ls-files``; binaries, found as git finds them by a NUL
byte in the first 8000 bytes or by failing to decode as UTF-8, are skipped) is scanned line
by line for

* a numbered reference to an issue or pull request of the project's own tracker: the word
  issue(s) followed by a number (with or without a hash sign), a hash-number in parentheses,
  ``PR`` + hash-number, "pull request" + number, and the word issue in the possessive after
  "the" (a pointer to a task description the reader cannot see);
* a pointer to a file outside the repository: the planning notes kept beside the checkout
  (the references and architecture markdown files, a path that starts at a sibling folder
  named shared, relative or not) and absolute paths of the development machine (the work
  and home directories at the file system's root).

Allowed, on purpose: the bare word "issue" in prose, the project's own issue tracker URL
(``.../issues`` with no number: where users report bugs), and a link to a numbered issue of
*another* project written as a URL (``github.com/<owner>/<repo>/issues/<n>``): a URL stands
alone and a reader can follow it, so it is a citation, not a pointer into private notes.
Facts that came from the planning notes are cited by their primary source (paper, standard,
library documentation) or by the place in this repository that records the measurement.

The patterns are written so that this file does not match itself; the example strings in
the self-check below are assembled from pieces for the same reason.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# (name, compiled pattern); case-insensitive, applied to each line
RULES: tuple[tuple[str, re.Pattern[str]], ...] = (
    ("numbered issue", re.compile(r"\bissues?\s*#?\s*\d+", re.IGNORECASE)),
    ("hash-number reference", re.compile(r"\(#\d+\)")),
    ("pull request number", re.compile(r"\b(?:PR\s*#\d+|pull\s+requests?\s*#?\s*\d+)", re.I)),
    ("possessive issue (a task description)", re.compile(r"\bthe\s+issue's\b", re.IGNORECASE)),
    ("file outside the repository", re.compile(r"\b(?:REFERENCES|ARCHITECTURE)\.md\b", re.I)),
    ("file outside the repository", re.compile(r"(?<![\w./-])(?:\.\./)*shared[/]")),
    ("machine path", re.compile(r"(?<![\w.])/(?:work|home)/")),
)


def _tracked_files() -> list[Path]:
    try:
        out = subprocess.run(
            ["git", "ls-files", "-z"],
            cwd=ROOT,
            capture_output=True,
            check=True,
            timeout=60,
        ).stdout
    except (OSError, subprocess.CalledProcessError) as exc:  # not a git checkout (an sdist)
        pytest.skip(f"git ls-files is unavailable here ({exc}); the scan needs a git checkout")
    return [ROOT / name for name in out.decode().split("\0") if name]


def _text(path: Path) -> str | None:
    """The file's text, or None for a binary (NUL byte in the first 8000 bytes, or not UTF-8)."""
    try:
        data = path.read_bytes()
    except (FileNotFoundError, IsADirectoryError):  # deleted in the work tree, or a submodule
        return None
    if b"\0" in data[:8000]:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def violations(text: str) -> list[tuple[int, str, str]]:
    """The offending lines of ``text``.

    Parameters
    ----------
    text : str
        A file's contents.

    Returns
    -------
    list of (int, str, str)
        ``(line number from 1, rule name, matched text)`` for each match, in line order.
    """
    found = []
    for n, line in enumerate(text.splitlines(), start=1):
        for name, pattern in RULES:
            m = pattern.search(line)
            if m:
                found.append((n, name, m.group(0)))
    return found


def test_tracked_files_speak_of_the_repository_only():
    files = _tracked_files()
    assert len(files) > 100, f"git ls-files listed only {len(files)} files under {ROOT}"
    problems = []
    scanned = 0
    for path in files:
        text = _text(path)
        if text is None:
            continue
        scanned += 1
        rel = path.relative_to(ROOT).as_posix()
        problems += [f"{rel}:{n}: {name}: {hit!r}" for n, name, hit in violations(text)]
    assert scanned > 100, f"only {scanned} tracked text files were scanned"
    assert not problems, (
        "the repository must speak of itself only (no issue numbers, no paths outside it); "
        "cite the primary source or the place here that records the fact:\n" + "\n".join(problems)
    )


# example strings assembled from pieces so that this file never matches its own rules
_ISSUE = "iss" + "ue"
_SHARED = "sha" + "red"
_BAD = [
    f"Placement benchmark ({_ISSUE} 20): deterministic",
    f"{_ISSUE.capitalize()} 12's case with real units",
    f"see {_ISSUE}s #3 and 4",
    "users ask for a flash model (" + "#417)",
    "merged in P" + "R #12",
    f"against the {_ISSUE}'s targets",
    f"measured in ``{_SHARED}/REFE" + "RENCES.md``",
    f"Conventions (../{_SHARED}/ARCHI" + "TECTURE.md):",
    "(REFERENCES" + ".md, 'LIDAR physics')",
    "written to /wo" + "rk/main/out",
]
_GOOD = [
    f'REPORT_URL = "https://github.com/simlunar/simlunar/{_ISSUE}s"',
    f"see https://github.com/mitsuba-renderer/mitsuba3/{_ISSUE}s/1234 for the bug",
    f"the {_ISSUE} of a periodical in which a work appeared",
    f"an {_ISSUE} tracker, a {_SHARED} folder, {_SHARED}_memory/ and a pre-{_SHARED}/key",
    "tests/test_layers.py checks the layer rules in CONTRIBUTING.md",
    f"default output /tmp/learned_check, a nested src/{_SHARED}/util.py",
    "colour #1f77b4 and comment #1 item",
]


@pytest.mark.parametrize("line", _BAD)
def test_rules_catch_pointers(line):
    assert violations(line), f"not caught: {line!r}"


@pytest.mark.parametrize("line", _GOOD)
def test_rules_allow_self_standing_text(line):
    assert not violations(line), f"flagged: {line!r} -> {violations(line)}"


def test_violations_name_the_line():
    text = "fine\n" + "also fine\n" + f"see {_ISSUE} 7 here\n"
    assert violations(text) == [(3, "numbered issue", f"{_ISSUE} 7")]
