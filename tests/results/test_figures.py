"""Writing a result folder's figures, on a hand-made scanner folder: the folder's files checked
against provenance (each refusal naming its file), figures redrawn only when their inputs change,
captions beside them, stale figures pruned."""

from __future__ import annotations

import json

import numpy as np
import pytest

from simlunar.config.yamlio import dump_yaml
from simlunar.errors import ResultFolderError
from simlunar.results import figures as rf
from simlunar.results.store import UnitCache, file_sha256

CONFIG = {"name": "s", "description": "first", "study": {"kind": "scanner", "metrics": ["mse"]}}
ROWS = "unit,mode,planner,trial,metric,value\n0,gray_code,,0,mse,2.0\n0,ambiguity_enhancement,wavelet,0,mse,1.0\n"


def _folder(tmp_path, config=CONFIG, rows=ROWS):
    (tmp_path / "config.yaml").write_text(dump_yaml(config))
    (tmp_path / "results.csv").write_text(rows)
    UnitCache(tmp_path).save("k0", {"sweep": {}, "index": 0}, {"x": np.zeros(2)})
    files = {n: file_sha256(tmp_path / n) for n in ("config.yaml", "results.csv")}
    (tmp_path / "provenance.json").write_text(json.dumps({"unit_keys": ["k0"], "files": files}))
    return tmp_path


def test_load_results(tmp_path):
    res = rf.load_results(_folder(tmp_path))
    assert res["config"] == CONFIG and res["dir"] == tmp_path
    assert [r["mode"] for r in res["rows"]] == ["gray_code", "ambiguity_enhancement"]
    assert [u["key"] for u in res["units"]] == ["k0"]
    assert rf.load_unit_arrays(tmp_path)["x"].tolist() == [0.0, 0.0]


def test_a_folder_that_is_not_a_finished_result_folder(tmp_path):
    with pytest.raises(
        ResultFolderError,
        match=r"missing config\.yaml\); run `simlunar run EXPERIMENT\.yaml` first$",
    ):
        rf.load_results(tmp_path)
    _folder(tmp_path)
    (tmp_path / "provenance.json").unlink()
    with pytest.raises(
        ResultFolderError, match=r"missing provenance\.json\); an unfinished run: rerun it"
    ):
        rf.load_results(tmp_path)
    (tmp_path / "f").write_text("")
    with pytest.raises(ResultFolderError, match=r"is a file, not a result folder$"):
        rf.load_results(tmp_path / "f")


def test_files_that_disagree_with_provenance_are_named(tmp_path):
    _folder(tmp_path)
    (tmp_path / "results.csv").write_text(ROWS + "0,gray_code,,1,mse,3.0\n")
    with pytest.raises(ResultFolderError) as info:
        rf.load_results(tmp_path)
    assert str(info.value).startswith(
        f"{tmp_path / 'results.csv'}: does not belong to this folder's results"
    )


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        ("unit,metric,value\n", r"results\.csv: no result rows$"),
        ("unit,metric\n0,mse\n", r"results\.csv: no 'value' column; not a simlunar results table$"),
        (
            "unit,metric,value\n0,mse,x\n",
            r"results\.csv: line 2: unit '0', value 'x' are not numbers$",
        ),
    ],
)
def test_bad_result_rows(tmp_path, rows, message):
    (tmp_path / "results.csv").write_text(rows)
    with pytest.raises(ResultFolderError, match=message):
        rf._read_rows(tmp_path / "results.csv")


def test_bad_provenance(tmp_path):
    p = tmp_path / "provenance.json"
    p.write_text("{")
    with pytest.raises(ResultFolderError, match=r"provenance\.json: not valid JSON"):
        rf._read_provenance(p)
    p.write_text('{"unit_keys": []}')
    with pytest.raises(
        ResultFolderError, match=r"no 'unit_keys' list; not a simlunar provenance file$"
    ):
        rf._read_provenance(p)


def test_figures_are_redrawn_only_when_their_inputs_change(tmp_path, monkeypatch):
    _folder(tmp_path)
    written = rf.write_figures(tmp_path)
    assert sorted(p.name for p in written) == ["captions.md", "scanner_errors.png"]
    stamp = json.loads((tmp_path / rf.STAMP).read_text())
    assert sorted(stamp["files"]) == ["captions.md", "scanner_errors.png"]
    assert "## scanner_errors" in (tmp_path / "figures" / "captions.md").read_text()

    def no_drawing(*a, **k):
        raise AssertionError("drawn again although nothing changed")

    monkeypatch.setattr(rf, "_draw", no_drawing)
    assert rf.write_figures(tmp_path) == written  # up to date: the same files, not redrawn
    with pytest.raises(AssertionError, match="drawn again"):
        rf.write_figures(tmp_path, force=True)
    with pytest.raises(AssertionError, match="drawn again"):
        rf.write_figures(tmp_path, formats=["pdf"])  # other formats: other inputs


def test_the_inputs_digest():
    res = {"config": CONFIG, "provenance": {"files": {"a": "1"}, "unit_keys": ["k0"]}}
    d = rf.figure_inputs(res, ["png"])
    assert rf.figure_inputs({**res, "config": {**CONFIG, "description": "other"}}, ["png"]) == d
    assert rf.figure_inputs(res, ["png", "pdf"]) != d
    assert (
        rf.figure_inputs({**res, "provenance": {"files": {"a": "2"}, "unit_keys": ["k0"]}}, ["png"])
        != d
    )


def _imported_closure(start: str, packages=("simlunar.plotting", "simlunar.results")) -> set:
    """``start`` and every module of ``packages`` it imports, directly or through one another,
    at the top or inside a function (read from the sources with ``ast``)."""
    import ast
    from pathlib import Path

    import simlunar

    root = Path(simlunar.__file__).parent

    def source(mod):
        rel = Path(*mod.split(".")[1:])
        return next((p for p in (root / rel.with_suffix(".py"), root / rel / "__init__.py")
                     if p.is_file()), None)  # fmt: skip

    def ours(mod):
        return any(mod == p or mod.startswith(p + ".") for p in packages)

    seen, todo = set(), [start]
    while todo:
        mod = todo.pop()
        path = source(mod)
        if mod in seen or path is None:
            continue
        seen.add(mod)
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                todo += [a.name for a in node.names if ours(a.name)]
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                todo += [node.module] if ours(node.module) else []
                # ``from simlunar.results import captions``: a module, not a name
                todo += [f"{node.module}.{a.name}" for a in node.names
                         if ours(f"{node.module}.{a.name}")]  # fmt: skip
    return seen


def test_the_drawing_code_is_every_plotting_and_results_module_the_figures_import():
    derived = _imported_closure("simlunar.results.figures")
    # the landing figures' summary and captions: missing from the former hand list, so a
    # change of them kept the landing figures "up to date"
    assert {"simlunar.plotting.landing_tables", "simlunar.results.captions_landing"} <= derived
    assert "simlunar.results.report" not in derived  # only the report uses it
    assert set(rf.DRAWING_MODULES) == derived


def test_a_change_of_the_drawing_code_changes_the_inputs_digest(monkeypatch):
    res = {"config": CONFIG, "provenance": {"files": {"a": "1"}, "unit_keys": ["k0"]}}
    d = rf.figure_inputs(res, ["png"])
    real = rf.file_sha256
    monkeypatch.setattr(rf, "file_sha256", lambda p: "x" if "captions_landing" in str(p)
                        else real(p))  # fmt: skip
    assert rf.figure_inputs(res, ["png"]) != d


def test_pruning_removes_figures_of_another_state(tmp_path):
    _folder(tmp_path)
    (tmp_path / "figures").mkdir()
    (tmp_path / "figures" / "old_figure.png").write_bytes(b"")
    written = rf.write_figures_pruned(tmp_path)
    assert sorted(p.name for p in (tmp_path / "figures").iterdir()) == sorted(
        p.name for p in written
    )


def test_captions_file(tmp_path):
    written = []
    rf.write_captions(tmp_path, {}, written)
    assert written == [] and not (tmp_path / "captions.md").exists()
    rf.write_captions(tmp_path, {"a": "First.", "b": "Second."}, written)
    assert (tmp_path / "captions.md").read_text() == (
        "# Figure captions\n\n## a\n\nFirst.\n\n## b\n\nSecond.\n"
    )
    assert written == [tmp_path / "captions.md"]
