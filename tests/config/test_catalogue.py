"""The experiment catalogue (simlunar/config/catalogue.py): every shipped experiment has a row
made from its own ``catalogue`` block, README and docs/experiments.md hold the generated table,
a run time never goes without its load."""

from __future__ import annotations

from pathlib import Path

import pytest
from pydantic import ValidationError

from simlunar.config.catalogue import (
    BEGIN,
    END,
    catalogue_block,
    catalogue_markdown,
    experiment_catalogue,
    main,
    run_time_text,
    update_catalogue,
)
from simlunar.config.schema import RunTimeCfg

ROOT = Path(__file__).resolve().parents[2]
EXPERIMENTS = ROOT / "experiments"


def test_every_shipped_experiment_says_what_it_shows():
    entries = experiment_catalogue(EXPERIMENTS)
    assert {e.name for e in entries} == {p.stem for p in EXPERIMENTS.glob("*.yaml")}
    missing = [e.name for e in entries if not e.shows]
    assert not missing, f"experiments without catalogue.shows: {missing}"


@pytest.mark.parametrize("doc", ["README.md", "docs/experiments.md"])
def test_the_documents_hold_the_generated_catalogue(doc):
    # a shipped experiment missing from a document's table, or a row kept by hand, fails here
    block = catalogue_block((ROOT / doc).read_text(encoding="utf-8"))
    assert block is not None, f"{doc}: no catalogue markers"
    assert block == catalogue_markdown(experiment_catalogue(EXPERIMENTS)), (
        f"{doc}: stale catalogue; run `python -m simlunar.config.catalogue`"
    )
    for name in (p.stem for p in EXPERIMENTS.glob("*.yaml")):
        assert f"| `{name}` |" in block


def test_a_new_experiment_without_a_catalogue_entry_shows_in_the_table_and_fails(tmp_path):
    exp = tmp_path / "experiments"
    exp.mkdir()
    (exp / "a.yaml").write_text(
        "name: a\nstudy: {kind: sampling}\nsweep: {seed: [1, 2, 3]}\n"
        "catalogue: {shows: 'A | B', run_time: {wall_min: 0.5, load: '2 cores, load 1'}}\n"
    )
    (exp / "b.yaml").write_text("name: b\nstudy: {kind: sampling, terrain_seeds: 4}\n")
    a, b = experiment_catalogue(exp)
    assert (a.name, a.shows, a.units) == ("a", "A | B", 3)
    assert (b.name, b.shows, b.units) == ("b", "", 4)
    md = catalogue_markdown([a, b])
    assert "| `a` | A \\| B | 3 | 30 s (2 cores, load 1) |" in md
    assert "| `b` | **(no catalogue entry" in md and "not re-measured" in md
    doc = tmp_path / "doc.md"
    doc.write_text(f"intro\n{BEGIN}\nold\n{END}\nend\n")
    assert update_catalogue(doc, exp, check=True) is True and "old" in doc.read_text()
    assert update_catalogue(doc, exp) is True
    assert update_catalogue(doc, exp) is False  # current: not rewritten
    text = doc.read_text()
    assert text.startswith("intro\n") and text.endswith(f"{END}\nend\n") and "`b`" in text
    plain = tmp_path / "plain.md"
    plain.write_text("no markers\n")
    with pytest.raises(ValueError, match="markers"):
        update_catalogue(plain, exp)


def test_run_time_text():
    assert run_time_text(RunTimeCfg()) == "not re-measured"
    assert (
        run_time_text(RunTimeCfg(note="partial runs only")) == "not re-measured (partial runs only)"
    )
    rt = RunTimeCfg(wall_min=20.8, load="2 cores, load 3-10", note="`--workers 2`")
    assert run_time_text(rt) == "20.8 min (2 cores, load 3-10; `--workers 2`)"
    rt = RunTimeCfg(wall_min=0.6, load="2 cores, load 4", first_run_min=1.25)
    assert run_time_text(rt) == "36 s (2 cores, load 4; first run, empty kernel cache: 75 s)"


def test_a_run_time_needs_its_load():
    with pytest.raises(ValidationError, match="load"):
        RunTimeCfg(wall_min=3.0)
    with pytest.raises(ValidationError, match="load"):
        RunTimeCfg(first_run_min=3.0)
    with pytest.raises(ValidationError):
        RunTimeCfg(wall_min=-1.0, load="x")


def test_bad_catalogue_block_names_the_file(tmp_path):
    (tmp_path / "x.yaml").write_text("catalogue: {shows: a, colour: red}\n")
    with pytest.raises(ValueError, match=r"x\.yaml: catalogue"):
        experiment_catalogue(tmp_path)


def test_main_check_reports_stale_documents(tmp_path, monkeypatch, capsys):
    (tmp_path / "experiments").mkdir()
    (tmp_path / "experiments" / "a.yaml").write_text("catalogue: {shows: a}\n")
    (tmp_path / "d.md").write_text(f"{BEGIN}\n{END}\n")
    monkeypatch.chdir(tmp_path)
    assert main(["--check", "d.md"]) == 1
    assert "stale" in capsys.readouterr().out
    assert main(["d.md"]) == 0 and main(["--check", "d.md"]) == 0


def test_every_shipped_experiment_has_a_run_time_or_says_why_not():
    # one run time per experiment: measured (with its load, checked by RunTimeCfg), or a note
    # that says why there is none (a model to train first, runs only in parts, not yet timed)
    silent = [
        e.name for e in experiment_catalogue(EXPERIMENTS) if e.run_time.wall_min is None
        and not e.run_time.note
    ]  # fmt: skip
    assert not silent, f"experiments with neither a measured run time nor a note: {silent}"
