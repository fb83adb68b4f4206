"""Paired per-terrain-seed comparisons of a LIDAR study's planners at equal scan time.

    PYTHONPATH=. python scripts/lidar_paired.py RESULTS_DIR --times 8 15 30 \
        --pairs lloyd_uniform:grid tour_wavelet:grid [--metric mse] [--by COLUMN]

For a steered beam (continuous scan times) each seed's error-vs-time curve is interpolated in
log-log at ``--times`` (:func:`simlunar.study.lidar.equal_time_errors`). With ``--equal-k`` the
rows are paired at the same density instead (sensors whose cost is frames, and sweep points of
a flash at equal frames). Per pair and time: the per-seed ratios, their geometric mean, wins
(first planner lower), the two-sided Wilcoxon signed-rank p of the log ratios and the two-sided
sign-test p (scipy.stats). ``--best`` names the planner of lowest geometric-mean error at each
time with its paired p against the runner-up.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np
from scipy import stats

from simlunar.study.lidar import equal_time_errors


def _rows(folder: Path) -> list[dict]:
    with (folder / "results.csv").open() as f:
        return list(csv.DictReader(f))


def paired(a: np.ndarray, b: np.ndarray, *, lower_is_better: bool = True) -> dict:
    """Per-seed comparison of ``a`` against ``b`` (finite pairs only)."""
    ok = np.isfinite(a) & np.isfinite(b) & (a > 0) & (b > 0)
    a, b = a[ok], b[ok]
    n = len(a)
    if n == 0:
        return {"n": 0}
    lr = np.log(a / b)
    wins = int((a < b).sum()) if lower_is_better else int((a > b).sum())
    nz = int((a != b).sum())
    sign = stats.binomtest(wins, nz, 0.5).pvalue if nz else 1.0
    wil = stats.wilcoxon(lr).pvalue if np.any(lr != 0) else 1.0
    return {"n": n, "ratio": float(np.exp(lr.mean())), "wins": wins, "sign_p": float(sign),
            "wilcoxon_p": float(wil), "per_seed": a / b}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("folder", type=Path)
    ap.add_argument("--times", type=float, nargs="*", default=[])
    ap.add_argument("--pairs", nargs="*", default=[])
    ap.add_argument("--metric", default="mse")
    ap.add_argument("--equal-k", action="store_true")
    ap.add_argument("--by", default=None, help="a sweep column: one comparison per value")
    ap.add_argument("--best", action="store_true")
    ap.add_argument("--higher", action="store_true", help="higher metric is better")
    ap.add_argument(
        "--cells",
        nargs="*",
        default=[],
        help="pairs of sweep cells 'TEXT/planner vs TEXT/planner' (TEXT: a substring of the --by "
        "column), paired by terrain_seed",
    )
    a = ap.parse_args()
    rows = [r for r in _rows(a.folder) if r["metric"] == a.metric]
    if a.cells:
        _cells(rows, a)
        return
    groups = sorted({r.get(a.by, "") for r in rows}) if a.by else [""]
    for g in groups:
        sub = [r for r in rows if not a.by or r.get(a.by, "") == g]
        if a.by:
            print(f"\n## {a.by} = {g}")
        if a.equal_k:
            _equal_k(sub, a)
        else:
            _equal_time(sub, a)


def _equal_time(rows, a) -> None:
    errs = equal_time_errors(rows, a.times, metric=a.metric)
    print("| pair | time (s) | seeds | geo-mean ratio | wins | Wilcoxon p | sign p |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for pair in a.pairs:
        x, y = pair.split(":")
        for j, t in enumerate(a.times):
            r = paired(errs[x][:, j], errs[y][:, j], lower_is_better=not a.higher)
            if r["n"] == 0:
                continue
            print(f"| {x} / {y} | {t:g} | {r['n']} | {r['ratio']:.3f} | {r['wins']}/{r['n']} | "
                  f"{r['wilcoxon_p']:.3g} | {r['sign_p']:.3g} |")  # fmt: skip
    if a.best:
        print("\n| time (s) | best | geo-mean | runner-up | ratio | wins | Wilcoxon p | sign p |")
        print("|---:|---|---:|---|---:|---:|---:|---:|")
        for j, t in enumerate(a.times):
            gm = {p: float(np.exp(np.nanmean(np.log(e[:, j])))) for p, e in errs.items()
                  if np.isfinite(e[:, j]).sum() == e.shape[0]}  # fmt: skip
            if len(gm) < 2:
                continue
            order = sorted(gm, key=gm.get)
            b, s = order[0], order[1]
            r = paired(errs[b][:, j], errs[s][:, j])
            print(f"| {t:g} | {b} | {gm[b]:.3g} | {s} | {r['ratio']:.3f} | {r['wins']}/{r['n']} "
                  f"| {r['wilcoxon_p']:.3g} | {r['sign_p']:.3g} |")  # fmt: skip


def _equal_k(rows, a) -> None:
    acc: dict = {}
    for r in rows:
        key = (r["planner"], int(float(r["k"])))
        acc.setdefault(key, {}).setdefault(int(float(r.get("unit", 0) or 0)), []).append(
            (float(r["value"]), float(r["seconds"]))
        )
    units = sorted({u for v in acc.values() for u in v})

    def arr(p, k):
        d = acc.get((p, k), {})
        v = np.array([np.mean([x for x, _ in d[u]]) if u in d else np.nan for u in units])
        s = np.array([np.mean([y for _, y in d[u]]) if u in d else np.nan for u in units])
        return v, s

    ks = sorted({k for _, k in acc})
    print(
        "| pair | k | seconds | seeds | mean A | mean B | geo-mean ratio | wins | Wilcoxon p "
        "| sign p |"
    )
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    for pair in a.pairs:
        x, y = pair.split(":")
        for k in ks:
            (va, sa), (vb, sb) = arr(x, k), arr(y, k)
            if not np.isfinite(va).any() or not np.isfinite(vb).any():
                continue
            if a.higher:  # binary / bounded scores: differences, not ratios
                ok = np.isfinite(va) & np.isfinite(vb)
                d = va[ok] - vb[ok]
                wins, nz = int((d > 0).sum()), int((d != 0).sum())
                sign = stats.binomtest(wins, nz, 0.5).pvalue if nz else 1.0
                wil = stats.wilcoxon(d).pvalue if np.any(d != 0) else 1.0
                print(f"| {x} / {y} | {k} | {np.nanmean(sa):.3g} / {np.nanmean(sb):.3g} | "
                      f"{ok.sum()} | {va[ok].mean():.3f} | {vb[ok].mean():.3f} | - | "
                      f"{wins}/{nz} | {wil:.3g} | {sign:.3g} |")  # fmt: skip
                continue
            r = paired(va, vb)
            print(f"| {x} / {y} | {k} | {np.nanmean(sa):.3g} / {np.nanmean(sb):.3g} | {r['n']} | "
                  f"{np.nanmean(va):.3g} | {np.nanmean(vb):.3g} | {r['ratio']:.3f} | "
                  f"{r['wins']}/{r['n']} | {r['wilcoxon_p']:.3g} | {r['sign_p']:.3g} |")  # fmt: skip


def _cells(rows, a) -> None:
    def cell(spec):
        text, planner = spec.rsplit("/", 1)
        d: dict = {}
        for r in rows:
            if text in r[a.by] and r["planner"] == planner:
                d.setdefault(int(r["terrain_seed"]), []).append(
                    (float(r["value"]), float(r["seconds"]))
                )
        return d

    print("| A | B | seconds A / B | seeds | mean A | mean B | wins A | Wilcoxon p | sign p |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|")
    for pair in a.cells:
        x, y = pair.split(" vs ")
        cx, cy = cell(x), cell(y)
        seeds = sorted(set(cx) & set(cy))
        va = np.array([np.mean([v for v, _ in cx[s]]) for s in seeds])
        vb = np.array([np.mean([v for v, _ in cy[s]]) for s in seeds])
        ta = np.mean([t for s in seeds for _, t in cx[s]])
        tb = np.mean([t for s in seeds for _, t in cy[s]])
        d = va - vb
        better = d > 0 if a.higher else d < 0
        wins, nz = int(better.sum()), int((d != 0).sum())
        sign = stats.binomtest(wins, nz, 0.5).pvalue if nz else 1.0
        wil = stats.wilcoxon(d).pvalue if np.any(d != 0) else 1.0
        print(f"| {x} | {y} | {ta:.3g} / {tb:.3g} | {len(seeds)} | {va.mean():.4g} | "
              f"{vb.mean():.4g} | {wins}/{nz} | {wil:.3g} | {sign:.3g} |")  # fmt: skip


if __name__ == "__main__":
    main()
