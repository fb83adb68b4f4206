"""What a run writes beside its units, on hand-made results: the score and samples-saved tables
(a strategy with half random's error scores 2.00 and is bold), scores.csv, the note when there
is no random, provenance's inputs, and the hash of the code that writes the tables."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path
from types import SimpleNamespace

import simlunar
from simlunar.results import summaries
from simlunar.results.records import WorkUnit
from simlunar.results.store import file_sha256

DENSITIES = [0.5, 0.25, 0.125]


def _units_and_rows(strategies=("random", "half"), seeds=2):
    units, records, rows = [], {}, []
    for i in range(seeds):
        cfg = {"name": "t", "terrain": {"seed_index": i},
               "study": {"strategies": list(strategies), "metrics": ["mse"]}}  # fmt: skip
        units.append(WorkUnit(i, f"k{i}", {"terrain.seed_index": i}, cfg))
        # a unit scores against random only (eq. 4.3): without it, no scores
        scores = (
            {"mse": {s: 1.0 + (s == "half") for s in strategies}} if "random" in strategies else {}
        )
        records[f"k{i}"] = {"meta": {"shape": [16, 16]}, "scores": scores}
        for s in strategies:
            for d in DENSITIES:
                k = int(d * 256)
                for t in range(2):
                    e = (1.0 if s != "half" else 0.5) * 100.0 / k
                    rows.append({"unit": str(i), "strategy": s, "density": str(d), "k": str(k),
                                 "trial": str(t), "metric": "mse", "value": repr(e)})  # fmt: skip
    return units, records, rows


CFG = SimpleNamespace(name="t", seed=1)


def test_score_and_samples_saved_tables(tmp_path):
    units, records, rows = _units_and_rows()
    md, tex = summaries._sampling_tables(CFG, units, records, rows, tmp_path)
    assert md.startswith("Scores pool 2 terrain seed(s) x 2 trials; [95 % interval]")
    assert "| MSE | 1.00 [1.00, 1.00] | **2.00 [2.00, 2.00]** |" in md.splitlines()
    # 1/4 and 1/8 interpolated; at 1/2 random would need 256 samples, past its densest budget
    assert "| Half | 2.00* | 2.00 | 2.00 | 2.00 (2) |" in md.splitlines()
    assert r"\textbf{2.00 [2.00, 2.00]}" in tex
    csv = (tmp_path / "scores.csv").read_text().splitlines()
    assert csv[0] == "point,terrain_seed,metric,strategy,reconstruction,score,ci_low,ci_high"
    assert ",all,mse,half,linear,2.0,2.0,2.0" in csv[-1]
    assert len(csv) == 1 + 2 * 2 + 2  # per seed and strategy, then pooled per strategy


def test_without_random_the_tables_say_why(tmp_path):
    (tmp_path / "scores.csv").write_text("stale")
    units, records, rows = _units_and_rows(strategies=("wavelet", "half"))
    md, tex = summaries._sampling_tables(CFG, units, records, rows, tmp_path)
    assert md.splitlines()[0] == (
        "No score table and no scores.csv: the scores (eq. 4.3) are errors relative to the "
        "random strategy, which study.strategies (wavelet, half) does not include; add random "
        "to get them. The errors are in results.csv."
    )
    assert md.rstrip().endswith("neither random nor grid among study.strategies.")
    assert tex.startswith("% No score table")
    assert not (tmp_path / "scores.csv").exists()  # the stale one removed


def test_inputs_and_names_are_listed_once():
    a = {"path": "dem.tif", "sha256": "aa"}
    units = [
        WorkUnit(0, "k0", {}, {"study": {"strategies": ["random", "grid"]}}, inputs={"terrain.file": a}),
        WorkUnit(1, "k1", {}, {"study": {"strategies": ["grid", "wavelet"]}}, inputs={"terrain.file": a}),
    ]  # fmt: skip
    assert summaries._inputs(units) == [{"key": "terrain.file", "path": "dem.tif", "sha256": "aa"}]
    assert summaries._names(units, "strategies") == ["random", "grid", "wavelet"]


def test_notes_name_each_dem_with_holes():
    checks = SimpleNamespace(holes=lambda: [{"file": "dem.tif", "nan_fraction": 0.0123}])
    (note,) = summaries._notes(checks, [], {})
    assert note.startswith("note: dem.tif: 1.23% of the DEM heights are NaN (holes)")


def test_provenance_records_the_run(tmp_path):
    units, records, _ = _units_and_rows(seeds=1)
    records["k0"]["meta"]["variant"] = "llvm_ad_rgb"
    (tmp_path / "config.yaml").write_text("name: t\n")
    (tmp_path / "results.csv").write_text("a\n")
    executor = SimpleNamespace(describe=lambda: "serial")
    checks = SimpleNamespace(holes=lambda: [])
    summaries._write_provenance(tmp_path, CFG, units, records, executor, 1, {"run": 2.0}, checks)
    prov = json.loads((tmp_path / "provenance.json").read_text())
    assert prov["experiment"] == "t" and prov["variant"] == "llvm_ad_rgb"
    assert prov["units"] == {"total": 1, "cached": 1, "computed": 0}
    assert prov["unit_keys"] == ["k0"] and prov["executor"] == "serial"
    assert prov["tables_code"] == summaries.tables_code()
    assert prov["files"] == {n: file_sha256(tmp_path / n) for n in ("config.yaml", "results.csv")}
    assert prov["simlunar"] == simlunar.__version__ and prov["timings"]["run"] == 2.0


def test_tables_code_hashes_the_table_modules(tmp_path, monkeypatch):
    root = Path(simlunar.__file__).parent
    h = hashlib.sha256()
    for mod in summaries._TABLE_MODULES:
        h.update(file_sha256(root.joinpath(*mod.split(".")[1:]).with_suffix(".py")).encode())
    assert summaries.tables_code() == h.hexdigest()
    # a changed table module changes the hash
    copy = tmp_path / "simlunar"
    shutil.copytree(root, copy, ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "plotting" / "tables.py").write_text(
        (copy / "plotting" / "tables.py").read_text() + "#\n"
    )
    monkeypatch.setattr(simlunar, "__file__", str(copy / "__init__.py"))
    assert summaries.tables_code.__wrapped__() != h.hexdigest()
