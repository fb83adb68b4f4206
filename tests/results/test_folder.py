"""A result folder: one configuration per folder (its first difference named when another
claims it), summary files that prove they belong to the units, figures and scans pruned to
what the folder's state shows."""

from __future__ import annotations

import hashlib
import json

import pytest

from simlunar.config.yamlio import dump_yaml
from simlunar.errors import ResultFolderError
from simlunar.results.folder import (
    RESULT_FILES,
    claim_folder,
    folder_complete,
    prune_figures,
    prune_scans,
    read_folder_config,
    scan_folders,
)
from simlunar.results.records import WorkUnit

CONFIG = {"name": "x", "description": "first", "seed": 1, "study": {"trials": 2},
          "figures": {"formats": ["png"]}}  # fmt: skip


def _claim(out, config):
    claim_folder(out, dump_yaml(config))


def test_an_empty_folder_takes_the_configuration(tmp_path):
    (tmp_path / ".hidden").write_text("")  # hidden files aside
    _claim(tmp_path, CONFIG)
    assert read_folder_config(tmp_path / "config.yaml") == CONFIG


def test_the_same_experiment_may_change_what_changes_no_number(tmp_path):
    _claim(tmp_path, CONFIG)
    again = {**CONFIG, "description": "second", "figures": {"formats": ["png", "pdf"]},
             "study": {"trials": 2, "score_region": "full"}}  # fmt: skip
    _claim(tmp_path, again)
    assert read_folder_config(tmp_path / "config.yaml") == again  # rewritten


def test_another_configuration_is_refused_naming_the_first_difference(tmp_path):
    _claim(tmp_path, CONFIG)
    before = (tmp_path / "config.yaml").read_text()
    with pytest.raises(ResultFolderError) as info:
        _claim(tmp_path, {**CONFIG, "study": {"trials": 3}})
    assert str(info.value) == (
        f"{tmp_path} holds the results of another configuration (study.trials: 2 in the "
        "folder, 3 now); choose another --out or delete the folder"
    )
    with pytest.raises(ResultFolderError, match=r"\(seed2: \"<absent>\" in the folder, 5 now\)"):
        _claim(tmp_path, {**CONFIG, "seed2": 5})
    assert (tmp_path / "config.yaml").read_text() == before


def test_a_folder_of_other_files_is_refused(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(ResultFolderError) as info:
        _claim(tmp_path, CONFIG)
    assert str(info.value) == (
        f"{tmp_path}: not empty and not a simlunar result folder (no config.yaml, found "
        "notes.txt); choose an empty or new folder"
    )
    assert not (tmp_path / "config.yaml").exists()


@pytest.mark.parametrize(
    ("text", "what"),
    [
        ("{{{", "not valid YAML, so the folder's configuration is unknown"),
        ("- 1\n", "not an experiment configuration"),
        ("name: x\nstudy: 3\n", "not an experiment configuration"),
    ],
)
def test_unreadable_folder_configurations(tmp_path, text, what):
    f = tmp_path / "config.yaml"
    f.write_text(text)
    with pytest.raises(ResultFolderError) as info:
        read_folder_config(f)
    assert str(info.value).startswith(f"{f}: {what}")
    assert str(info.value).endswith("choose another --out or delete the folder")


def _finish(out, keys):
    files = {}
    for name in RESULT_FILES[1:]:
        (out / name).write_text(name)
        files[name] = hashlib.sha256(name.encode()).hexdigest()
    (out / "provenance.json").write_text(json.dumps({"unit_keys": keys, "files": files}))


def test_a_folder_is_complete_when_its_files_match_its_provenance(tmp_path):
    assert not folder_complete(tmp_path, ["a"])  # no provenance
    _finish(tmp_path, ["a", "b"])
    assert folder_complete(tmp_path, ["a", "b"])
    assert not folder_complete(tmp_path, ["a"])  # other units
    (tmp_path / "scores.md").write_text("edited")
    assert not folder_complete(tmp_path, ["a", "b"])
    (tmp_path / "provenance.json").write_text("[1, 2]")
    assert not folder_complete(tmp_path, ["a", "b"])


def test_prune_figures_keeps_what_is_kept_and_other_files(tmp_path):
    fig = tmp_path / "figures"
    fig.mkdir()
    for name in ("a.png", "b.PDF", "c.png", "notes.txt"):
        (fig / name).write_text("")
    removed = prune_figures(tmp_path, keep=[tmp_path / "elsewhere" / "a.png"])
    assert [p.name for p in removed] == ["b.PDF", "c.png"]
    assert sorted(p.name for p in fig.iterdir()) == ["a.png", "notes.txt"]
    assert prune_figures(tmp_path / "none", keep=()) == []


def _unit(i, key, save):
    return WorkUnit(i, key, {}, {"study": {"save_scans": save}})


def test_scan_folders_one_per_key():
    units = [
        _unit(0, "k0", True),
        _unit(1, "k0", True),
        _unit(2, "k2", False),
        _unit(3, "k3", True),
    ]
    assert scan_folders(units) == {"unit0": "k0", "unit3": "k3"}
    assert scan_folders([WorkUnit(0, "k", {}, {})]) == {}


def test_prune_scans_removes_exports_of_no_unit(tmp_path):
    scans = tmp_path / "scans"
    for name in ("unit0", "unit7"):
        (scans / name).mkdir(parents=True)
    (scans / "readme.txt").write_text("")  # not the runner's: kept
    removed = prune_scans(tmp_path, {"unit0": "k0"})  # unit0's export is incomplete too
    assert sorted(p.name for p in removed) == ["unit0", "unit7"]
    assert sorted(p.name for p in scans.iterdir()) == ["readme.txt"]
    (scans / "readme.txt").unlink()
    (scans / "unit1").mkdir()
    prune_scans(tmp_path, {})
    assert not scans.exists()  # an empty scans/ goes too
