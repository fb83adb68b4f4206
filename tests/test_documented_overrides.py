"""Every ``simlunar run experiments/X.yaml --set ...`` written in an experiment's header comment or
in README / REPRODUCTION / docs names keys the experiment schema accepts.

A scanner study once documented ``--set study.terrain_seeds=5`` in its YAML header and in
REPRODUCTION.md: the scanner schema has no such key (its seeds are a sweep), so the documented
intervals run failed at once. ``tests/test_docs_commands.py`` runs the fenced bash blocks of
README and docs/ on shrunk experiments; this test reads the commands those blocks do not cover
(YAML comments, inline code in prose, REPRODUCTION.md) and validates their overrides without
running anything.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from simlunar.config.loading import load_experiment
from simlunar.config.yamlio import parse_set
from simlunar.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]
RUN = re.compile(r"simlunar run (experiments/[\w/.-]+\.yaml)")


def _commands_in_yaml(path: Path) -> list[tuple[str, str]]:
    """(experiment, command text) for the header comment of an experiment YAML; an override
    written without the command (``# Intervals: --set ...``) applies to the file itself."""
    comment = " ".join(
        line.lstrip("#").strip() for line in path.read_text().splitlines() if line.startswith("#")
    )
    rel = path.relative_to(ROOT).as_posix()
    found = [(m.group(1), comment[m.start() :]) for m in RUN.finditer(comment)]
    if "--set" in comment and not found:
        found = [(rel, comment)]
    return found


def _commands_in_markdown(path: Path) -> list[tuple[str, str]]:
    """(experiment, command text) for every ``simlunar run experiments/...`` in a markdown file,
    fenced or inline; a fenced command's backslash continuations are joined."""
    text = path.read_text().replace("\\\n", " ")
    fenced = re.findall(r"```[^\n]*\n(.*?)```", text, re.S)
    prose = re.sub(r"```.*?```", "", text, flags=re.S)
    inline = re.findall(r"(?<!`)`([^`]+)`(?!`)", prose)
    lines = [line for block in fenced for line in block.splitlines()]
    lines += [" ".join(span.split()) for span in inline]  # an inline span may wrap lines
    out = []
    for line in lines:
        m = RUN.search(line)
        if m:
            out.append((m.group(1), line[m.start() :]))
    return out


def _overrides(command: str) -> list[str]:
    """The ``--set`` values of one command (stops at a comment, a pipe or the next command)."""
    command = re.split(r"\s(?:#|\||&&|;)\s", command)[0]
    try:
        words = shlex.split(command)
    except ValueError:  # an unbalanced quote: the prose around an inline command
        words = command.split()
    return [words[i + 1] for i, w in enumerate(words[:-1]) if w == "--set"]


def _documented() -> list[tuple[str, str, str]]:
    items = []
    for yml in sorted((ROOT / "experiments").rglob("*.yaml")):
        items += [(yml.name, exp, c) for exp, c in _commands_in_yaml(yml)]
    for md in [ROOT / "README.md", ROOT / "REPRODUCTION.md", *sorted((ROOT / "docs").glob("*.md"))]:
        items += [(md.name, exp, c) for exp, c in _commands_in_markdown(md)]
    return [(src, exp, c) for src, exp, c in items if _overrides(c)]


DOCUMENTED = _documented()


def test_the_documents_do_hold_override_commands():
    # the scan itself must find what it is meant to check (the DLP intervals run among them)
    sources = {src for src, _, _ in DOCUMENTED}
    assert {"scanner_ambiguity_dlp.yaml", "REPRODUCTION.md"} <= sources
    assert len(DOCUMENTED) >= 5


@pytest.mark.parametrize(
    "source, experiment, command",
    DOCUMENTED,
    ids=[f"{s}:{e.split('/')[-1]}:{i}" for i, (s, e, _) in enumerate(DOCUMENTED)],
)
def test_documented_overrides_name_valid_keys(source, experiment, command):
    path = ROOT / experiment
    assert path.exists(), f"{source} names {experiment}, which does not exist"
    load_experiment(path, parse_set(_overrides(command)))


def test_an_invalid_documented_key_is_caught():
    # the bug this module is named after: the scanner schema has no study.terrain_seeds
    bad = "simlunar run experiments/scanner_ambiguity_dlp.yaml --set study.terrain_seeds=5"
    with pytest.raises(ConfigError, match="terrain_seeds"):
        load_experiment(ROOT / "experiments/scanner_ambiguity_dlp.yaml", parse_set(_overrides(bad)))
