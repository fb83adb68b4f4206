"""scores.md read back as blocks, and every table of it written as CSV."""

from __future__ import annotations

import csv

from fake_unit import fake_unit

from simlunar.config.schema import ExperimentCfg
from simlunar.pipeline.runner import run_experiment
from simlunar.results.md_tables import parse_markdown, table_slug, write_table_csvs

MD = """Scores pool 1 seed.
Second line of the paragraph.

### demo: scores (random = 1)

| Metric | Random | Wavelet, Lloyd |
|---|---:|:---:|
| MSE | 1.00 [1.00, 1.00] | **2.61 [0.90, 6.67]** |
| a \\| b | – | 3 |

### demo: samples saved vs Grid at equal MSE

| Strategy | 1/4 |
|---|---:|
| Random | 0.59* |
"""


def test_parse_markdown_blocks_in_order():
    blocks = parse_markdown(MD)
    assert [b.kind for b in blocks] == ["paragraph", "heading", "table", "heading", "table"]
    assert blocks[0].text == "Scores pool 1 seed. Second line of the paragraph."
    assert (blocks[1].level, blocks[1].text) == (3, "demo: scores (random = 1)")
    t = blocks[2]
    assert t.rows == [
        ["Metric", "Random", "Wavelet, Lloyd"],
        ["MSE", "1.00 [1.00, 1.00]", "**2.61 [0.90, 6.67]**"],
        ["a | b", "–", "3"],  # an escaped bar is a character of the cell
    ]
    assert t.align == ["left", "right", "center"]


def test_table_slug():
    assert table_slug("demo: samples saved vs Grid at equal MSE") == (
        "demo_samples_saved_vs_grid_at_equal_mse"
    )
    assert table_slug("  ***  ") == "table"


def test_csv_round_trip_and_stale_files_removed(tmp_path):
    (tmp_path / "tables").mkdir()
    (tmp_path / "tables" / "old_table.csv").write_text("x\n")
    paths = write_table_csvs(tmp_path, MD)
    assert [p.name for p in paths] == [
        "demo_scores_random_1.csv",
        "demo_samples_saved_vs_grid_at_equal_mse.csv",
    ]
    with paths[0].open(newline="") as f:
        rows = list(csv.reader(f))
    assert rows == parse_markdown(MD)[2].rows  # commas inside cells survive
    assert not (tmp_path / "tables" / "old_table.csv").exists()
    # no table left: the folder goes
    assert write_table_csvs(tmp_path, "just text\n") == []
    assert not (tmp_path / "tables").exists()


def test_same_heading_twice_and_no_heading(tmp_path):
    table = "| a |\n|---|\n| 1 |\n"
    md = f"{table}\n### t\n\n{table}\n### t\n\n{table}"
    names = [p.name for p in write_table_csvs(tmp_path, md)]
    assert names == ["table_1.csv", "t.csv", "t_2.csv"]


def test_a_run_writes_every_table_of_scores_md_as_csv(tmp_path):
    cfg = ExperimentCfg.model_validate(
        {
            "name": "csv_test",
            "seed": 3,
            "terrain": {"preset": "aerial_1", "scale": 0.125},
            "study": {
                "strategies": ["random", "grid", "wavelet"],
                "densities": [0.5, 0.25, 0.125],
                "trials": 2,
                "metrics": ["mse"],
            },
        }
    )
    out = tmp_path / "o"
    run_experiment(cfg, out, compute=fake_unit, progress=False, figures=False)
    md = (out / "scores.md").read_text()
    tables = [b for b in parse_markdown(md) if b.kind == "table"]
    files = sorted((out / "tables").glob("*.csv"))
    assert len(files) == len(tables) >= 2
    assert any("samples_saved_vs_grid" in p.name for p in files)
    got = {tuple(map(tuple, csv.reader(p.read_text().splitlines()))) for p in files}
    assert got == {tuple(map(tuple, t.rows)) for t in tables}
