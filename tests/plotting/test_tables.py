"""Score tables in the paper's Table 1 / Table 2 layouts."""

from __future__ import annotations

from simlunar.plotting.tables import score_tables

# paper Table 2 (moonyard), MSE/GRAD/SAL rows, Grid/Random/Gradient/Entropy/Wavelet
PAPER_T2 = {
    "mse": {"grid": 1.1, "random": 1.0, "gradient": 1.09, "entropy": 1.15, "wavelet": 1.33},
    "grad": {"grid": 0.82, "random": 1.0, "gradient": 1.21, "entropy": 1.32, "wavelet": 1.42},
}
STRATS = ["random", "grid", "gradient", "entropy", "wavelet"]


def test_single_scene_is_table2_layout():
    md, tex = score_tables(
        [("moonyard", PAPER_T2)], strategies=STRATS, metrics=["mse", "grad"], title="t2"
    )
    lines = md.splitlines()
    assert "| Metric | Random | Grid | Gradient | Entropy | Wavelet |" in lines
    assert "| MSE | 1.00 | 1.10 | 1.09 | 1.15 | **1.33** |" in lines
    assert "| GRAD | 1.00 | 0.82 | 1.21 | 1.32 | **1.42** |" in lines
    assert "MSE & 1.00 & 1.10 & 1.09 & 1.15 & \\textbf{1.33} \\\\" in tex
    assert tex.count("\\begin{tabular}{lrrrrr}") == 1
    assert "\\toprule" in tex and "\\bottomrule" in tex


def test_several_scenes_is_table1_layout_per_metric():
    # paper Table 1, MSE: scene 1 1/1.02/0.88/0.87/1.11, scene 3 1/0.91/0.83/0.80/1.21
    s1 = {"mse": dict(zip(STRATS, [1, 1.02, 0.88, 0.87, 1.11]))}
    s3 = {"mse": dict(zip(STRATS, [1, 0.91, 0.83, 0.80, 1.21]))}
    md, tex = score_tables(
        [("aerial_1", s1), ("aerial_3", s3)], strategies=STRATS, metrics=["mse"], title="t1"
    )
    # paper Table 1 blocks: the scene names its columns, one row per metric
    assert (
        "| aerial_1 | Random | Grid | Gradient | Entropy | Wavelet |\n|---|---:|---:|---:|---:|---:|\n| MSE | 1.00 | 1.02 | 0.88 | 0.87 | **1.11** |"
        in md
    )
    assert (
        "aerial\\_3 & Random & Grid & Gradient & Entropy & Wavelet \\\\\n\\midrule\nMSE & 1.00 & 0.91 & 0.83 & 0.80 & \\textbf{1.21} \\\\"
        in tex
    )
    # then per metric, scenes as rows
    assert "| Scene | Random | Grid | Gradient | Entropy | Wavelet |" in md
    assert "| aerial_1 | 1.00 | 1.02 | 0.88 | 0.87 | **1.11** |" in md
    assert "| aerial_3 | 1.00 | 0.91 | 0.83 | 0.80 | **1.21** |" in md
    assert "aerial\\_1 &" in tex  # escaped for LaTeX


def test_missing_scores_show_a_dash():
    md, tex = score_tables(
        [("x", {"mse": {"random": 1.0}})], strategies=["random", "grid"], metrics=["mse"]
    )
    assert "| MSE | **1.00** | – |" in md
    assert "--" in tex and "–" not in tex


def test_intervals_print_and_bold_only_where_marked():
    from simlunar.plotting.tables import Cell

    scores = {
        "mse": {
            "random": Cell(1.0, 1.0, 1.0),
            "grid": Cell(1.291, 1.2149, 1.37),
            "wavelet": Cell(1.25, 1.1, 1.4),
        },
        "grad": {
            "random": Cell(1.0, 1.0, 1.0),
            "grid": Cell(0.9, 0.8, 1.0),
            "wavelet": Cell(1.42, 1.3, 1.5, bold=True),
        },
    }
    md, tex = score_tables(
        [("x", scores)], strategies=["random", "grid", "wavelet"], metrics=["mse", "grad"],
        note="how",
    )  # fmt: skip
    # the best MSE is not bold: nothing marked it (its lead is not significant)
    assert "| MSE | 1.00 [1.00, 1.00] | 1.29 [1.21, 1.37] | 1.25 [1.10, 1.40] |" in md
    assert "| GRAD | 1.00 [1.00, 1.00] | 0.90 [0.80, 1.00] | **1.42 [1.30, 1.50]** |" in md
    assert "\\textbf{1.42 [1.30, 1.50]}" in tex and "\\textbf{1.29" not in tex
    assert md.startswith("how\n") and tex.startswith("% how")


def test_samples_saved_table():
    from simlunar.plotting.tables import samples_saved_tables

    entry = {
        "label": "",
        "reference": "random",
        "metric": "mse",
        "strategies": ["random", "grid"],
        "ks": [100, 25],
        "densities": [0.5, 0.125],
        "factor": {"random": [1.0, 1.0], "grid": [1.234, 12.34]},
        "flag": {"random": [0, 0], "grid": [1, 0]},
        "summary": {"random": 1.0, "grid": 12.34},
        "n_summary": {"random": 2, "grid": 1},
    }
    md, tex = samples_saved_tables([entry], title="t")
    assert "| Strategy | 1/2 | 1/8 | geo. mean (n) |" in md
    assert "| Grid | 1.23* | 12.3 | 12.34 (1) |" in md  # * = extrapolated
    assert "| Random |" not in md  # the reference is not its own row
    assert "Grid & 1.23* & 12.3 & 12.34 (1) \\\\" in tex
    assert samples_saved_tables([], title="t") == ("", "")


def test_headroom_table_gives_t_intervals_over_seeds_by_hand():
    from simlunar.plotting.tables import headroom_tables

    entry = {
        "label": "", "oracle": "oracle_greedy", "metric": "mse", "strategies": ["wavelet_lloyd"],
        "seeds": [0, 1, 2],
        "saved": {"oracle_greedy": [2.0, 2.0, 2.0], "wavelet_lloyd": [1.1, 1.2, 1.3]},
        "captured": {"wavelet_lloyd": [0.1, 0.2, 0.3]},
    }  # fmt: skip
    md, tex = headroom_tables([entry], title="t")
    # saved, in log space: ln 1.1, ln 1.2, ln 1.3 -> mean 0.1799987, s = 0.0835512,
    # half width t(0.975, 2) s / sqrt(3) = 4.302653 * 0.0482383 = 0.207553:
    # exp(0.1800) = 1.197, [exp(-0.02755), exp(0.38755)] = [0.973, 1.473]
    # captured [0.1, 0.2, 0.3]: 0.2 +- 4.302653 * 0.1 / sqrt(3) = 0.2 +- 0.248414
    assert (
        "| Wavelet, Lloyd | 1.20 [0.97, 1.47] | 1.10–1.30 | 0.20 [-0.05, 0.45] | 0.10–0.30 |" in md
    )
    # the oracle: every seed 2.0 -> a zero-width interval; it is the bound
    assert "| 2.00 [2.00, 2.00] | 2.00–2.00 | 1 (bound) |" in md
    assert "95 % Student t interval" in md
    assert "1.10--1.30" in tex and "–" not in tex


def test_headroom_table_with_one_seed_prints_the_value_alone():
    from simlunar.plotting.tables import headroom_tables

    entry = {
        "label": "", "oracle": "oracle_greedy", "metric": "mse", "strategies": ["wavelet_lloyd"],
        "seeds": [0], "saved": {"oracle_greedy": [2.0], "wavelet_lloyd": [1.25]},
        "captured": {"wavelet_lloyd": [float("nan")]},
    }  # fmt: skip
    md, _ = headroom_tables([entry], title="t")
    # one seed: no range column (it would be empty), but a seed without a value is counted
    assert "| Strategy | saved vs Uniform Lloyd | headroom captured | seeds: range |" in md
    assert "| Wavelet, Lloyd | 1.25 | – | (0 of 1 seeds) |" in md


def test_seeds_without_a_value_are_counted_not_hidden():
    from simlunar.plotting.tables import paired_saved_tables

    entry = {"label": "", "metric": "mse", "strategies": ["a", "b"], "seeds": [0, 1, 2],
             "saved": {"a": [1.1, float("nan"), 1.3], "b": [float("nan"), 0.9, float("nan")]}}  # fmt: skip
    md, _ = paired_saved_tables([entry], title="t")
    # a: exp(mean(ln 1.1, ln 1.3)) = 1.196 over 2 of the 3 seeds; b: one value left
    assert "| 1.20 [" in md and "| 1.10–1.30 (2 of 3 seeds) |" in md
    assert "| 0.90 | (1 of 3 seeds) |" in md


def test_paired_saved_table_without_an_oracle_by_hand():
    from simlunar.plotting.tables import paired_saved_tables

    entry = {"label": "", "metric": "mse", "strategies": ["grid", "wavelet_lloyd"],
             "seeds": [0, 1, 2],
             "saved": {"grid": [0.9, 0.9, 0.9], "wavelet_lloyd": [1.1, 1.2, 1.3]}}  # fmt: skip
    md, tex = paired_saved_tables([entry], title="t")
    # as in the headroom table: exp(mean ln) = 1.197, [0.973, 1.473]
    assert "| Wavelet, Lloyd | 1.20 [0.97, 1.47] | 1.10–1.30 |" in md
    assert "| Grid | 0.90 [0.90, 0.90] | 0.90–0.90 |" in md
    assert "paired by seed (3 terrain seeds)" in md and "1.10--1.30" in tex
    assert paired_saved_tables([], title="t") == ("", "")


def test_a_study_of_the_reference_alone_prints_no_empty_table():
    # one layout (the reference itself): nothing is compared with it, so neither the
    # samples-saved nor the paired table is printed (not a header without rows)
    from simlunar.plotting.tables import paired_saved_tables, samples_saved_tables

    alone = {"label": "", "reference": "lloyd_uniform", "metric": "mse",
             "strategies": ["lloyd_uniform"], "ks": [100], "densities": [0.5],
             "factor": {"lloyd_uniform": [1.0]}, "flag": {"lloyd_uniform": [0]},
             "summary": {"lloyd_uniform": 1.0}, "n_summary": {"lloyd_uniform": 1}}  # fmt: skip
    assert samples_saved_tables([alone], title="t") == ("", "")
    paired = {"label": "", "metric": "mse", "strategies": ["lloyd_uniform"], "seeds": [0, 1],
              "saved": {}}  # fmt: skip
    assert paired_saved_tables([paired], title="t") == ("", "")
    # beside a table with rows, the empty one is left out and the other kept
    other = {**paired, "label": "b", "strategies": ["grid"], "saved": {"grid": [0.9, 0.8]}}
    md, _ = paired_saved_tables([paired, other], title="t")
    assert md.count("### ") == 1 and "t: b: samples saved" in md
