"""Pooling a sampling experiment per reconstruction, and each reconstruction against linear."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from simlunar.results import aggregate

KS = [256, 128, 64, 32]  # densities 1/4 .. 1/32 of a 32 x 32 grid
DENS = [k / 1024 for k in KS]


def _records(n_seeds, recons=("linear", "smooth")):
    study = {"strategies": ["grid", "wavelet"], "metrics": ["mse"],
             "reconstructions": list(recons)}  # fmt: skip
    return [
        {"sweep": {}, "config": {"name": "t", "study": study, "terrain": {"seed_index": j}},
         "meta": {"shape": [32, 32]}}
        for j in range(n_seeds)
    ]  # fmt: skip


def _rows(gains):
    """linear: e = 1 / k exactly; reconstruction 'smooth' on seed j: e = 1 / (gains[j] k), so
    linear needs gains[j] times the samples for its error (a power law interpolates exactly)."""
    rows = []
    for j, g in enumerate(gains):
        for s in ("grid", "wavelet"):
            for d, k in zip(DENS, KS):
                for t in range(2):
                    for r, e in (("linear", 1.0 / k), ("smooth", 1.0 / (g * k))):
                        rows.append({"unit": j, "strategy": s, "reconstruction": r, "density": d,
                                     "k": k, "trial": t, "metric": "mse", "value": e})  # fmt: skip
    return rows


def test_points_are_per_reconstruction_and_read_their_own_rows():
    recs = _records(2)
    points = aggregate.group_points(recs)
    assert [(p.reconstruction, p.label) for p in points] == [
        ("linear", "reconstruction=linear"),
        ("smooth", "reconstruction=smooth"),
    ]
    rows = _rows([2.0, 4.0])
    _, ks, lin = aggregate.error_arrays(rows, points[0], "mse")
    _, _, smo = aggregate.error_arrays(rows, points[1], "mse")
    assert ks == KS
    np.testing.assert_allclose(lin["grid"][0, :, 0], [1 / k for k in KS])
    np.testing.assert_allclose(smo["grid"][1, :, 0], [1 / (4 * k) for k in KS])
    # linear alone: one point per sweep point, rows without the column are linear's
    (one,) = aggregate.group_points(_records(1, ("linear",)))
    plain = [{k: v for k, v in r.items() if k != "reconstruction"} for r in _rows([2.0])
             if r["reconstruction"] == "linear"]  # fmt: skip
    _, _, e = aggregate.error_arrays(plain, one, "mse")
    assert one.label == "t" and e["wavelet"].shape == (1, 4, 2)


def test_reconstruction_vs_linear_is_paired_by_seed_with_a_t_interval():
    recs = _records(2)
    rows = _rows([2.0, 4.0])
    points = aggregate.summarise(recs, rows, seed=0, n_boot=10)
    (entry,) = aggregate.reconstruction_saved_entries(points, rows)
    assert entry["reconstructions"] == ["smooth"] and entry["seeds"] == [0, 1]
    # per seed: exactly the gain (the densest k is outside linear's range and left out)
    np.testing.assert_allclose(entry["saved"]["smooth"]["grid"], [2.0, 4.0])
    from simlunar.plotting.tables import reconstruction_saved_tables, seed_summary_numbers

    m, lo, hi, n = seed_summary_numbers(entry["saved"]["smooth"]["grid"], log=True)
    logs = np.log([2.0, 4.0])
    half = stats.t.ppf(0.975, 1) * logs.std(ddof=1) / math.sqrt(2)
    assert (m, n) == (pytest.approx(math.sqrt(8)), 2)
    assert lo == pytest.approx(math.exp(logs.mean() - half))
    assert hi == pytest.approx(math.exp(logs.mean() + half))
    md, tex = reconstruction_saved_tables([entry], title="t")
    assert f"| Grid | {m:.2f} [{lo:.2f}, {hi:.2f}] | 2.00–4.00 |" in md
    assert "smooth vs linear" in md.lower() and "\\begin{table}" in tex


def test_no_comparison_without_linear_or_without_another_reconstruction():
    rows = _rows([2.0])
    pts = aggregate.summarise(_records(1, ("linear",)), rows, seed=0, n_boot=10)
    assert aggregate.reconstruction_saved_entries(pts, rows) == []
    only = [r for r in rows if r["reconstruction"] == "smooth"]
    pts = aggregate.summarise(_records(1, ("smooth",)), only, seed=0, n_boot=10)
    assert aggregate.reconstruction_saved_entries(pts, only) == []


def test_the_sweep_figure_gets_one_point_per_sweep_value():
    import matplotlib.pyplot as plt

    from simlunar.results import sampling_figures

    recs, rows = [], []
    for i, (elev, gains) in enumerate(((15, [2.0, 4.0]), (60, [1.0, 1.0]))):
        for j, rec in enumerate(_records(2)):
            rec["sweep"] = {"render.light.elevation_deg": elev, "terrain.seed_index": j}
            recs.append(rec)
        for r in _rows(gains):
            rows.append({**r, "unit": 2 * i + r["unit"]})
    points = aggregate.summarise(recs, rows, seed=0, n_boot=10)
    res = {"config": {"sweep": {"render.light.elevation_deg": [15, 60]}}, "rows": rows}
    drawn, captions = [], {}
    sampling_figures._reconstruction_figure(
        res, points, lambda fig, stem: drawn.append((fig, stem)), captions
    )
    ((fig, stem),) = drawn
    assert stem == "reconstruction_saved_vs_elevation_deg"
    line = next(ln for ln in fig.axes[0].get_lines() if ln.get_label() == "Smooth")
    np.testing.assert_allclose(line.get_xdata(), [15, 60], atol=1)  # dodged a little
    np.testing.assert_allclose(line.get_ydata(), [math.sqrt(8), 1.0])
    assert (
        "2 terrain seeds (marker); error bars: its two-sided 95 % Student t interval"
        in (captions[stem])
    )
    plt.close(fig)


def test_layout_and_reconstruction_together_vs_uniform_lloyd_and_linear():
    # uniform Lloyd + linear: e = 1 / k; the wavelet layout saves 1.5x with linear; the
    # reconstruction 'smooth' saves g[j] on every layout: together 1.5 g[j] (power laws:
    # the interpolation is exact)
    gains = [2.0, 4.0]
    study = {"strategies": ["lloyd_uniform", "wavelet"], "metrics": ["mse"],
             "reconstructions": ["linear", "smooth"]}  # fmt: skip
    recs = [{"sweep": {}, "config": {"name": "t", "study": study, "terrain": {"seed_index": j}},
             "meta": {"shape": [32, 32]}} for j in range(2)]  # fmt: skip
    rows = [
        {"unit": j, "strategy": s, "reconstruction": r, "density": d, "k": k, "trial": t,
         "metric": "mse", "value": 1.0 / (f * k * (g if r == "smooth" else 1.0))}
        for j, g in enumerate(gains) for s, f in (("lloyd_uniform", 1.0), ("wavelet", 1.5))
        for d, k in zip(DENS, KS) for t in range(2) for r in ("linear", "smooth")
    ]  # fmt: skip
    points = aggregate.summarise(recs, rows, seed=0, n_boot=10)
    (entry,) = aggregate.reconstruction_saved_entries(points, rows)
    joint = entry["joint"]
    assert list(joint) == ["linear", "smooth"]
    np.testing.assert_allclose(joint["linear"]["lloyd_uniform"], [1.0, 1.0])
    np.testing.assert_allclose(joint["linear"]["wavelet"], [1.5, 1.5])
    np.testing.assert_allclose(joint["smooth"]["lloyd_uniform"], gains)
    np.testing.assert_allclose(joint["smooth"]["wavelet"], [3.0, 6.0])
    from simlunar.plotting.tables import reconstruction_saved_tables

    md, tex = reconstruction_saved_tables([entry], title="t")
    assert "\\begin{table}" in tex
    assert "layout + reconstruction vs Uniform Lloyd + linear at equal MSE" in md
    assert "| Wavelet | 1.50 [1.50, 1.50] | 1.50–1.50 | 4.24" in md
    # without uniform Lloyd there is no such table
    (plain,) = aggregate.reconstruction_saved_entries(
        aggregate.summarise(_records(2), _rows(gains), seed=0, n_boot=10), _rows(gains)
    )
    assert plain["joint"] == {}
    assert "Uniform Lloyd + linear" not in reconstruction_saved_tables([plain], title="t")[0]
