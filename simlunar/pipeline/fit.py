"""Fit the feature-combination coefficients on a result folder's scenes (paper section 4.1).

``python -m simlunar.pipeline.fit RESULTS --train-seeds 1 2 3 --test-seeds 4 5 6`` reads the
cached guide image and depth of each work unit of a sampling experiment swept over ``seed``
(e.g. ``experiments/fit_combination.yaml``), fits the coefficients of the combined maps by
Nelder-Mead (:func:`simlunar.planner.fit_combination`) on the training seeds, and scores the
fitted coefficients, the equal-weight start and each map alone on the held-out seeds with the
same protocol (:func:`simlunar.planner.score_combination`). Writes ``fit.json`` and ``fit.md``
into the result folder (``fit_lloyd.*`` with ``--placement lloyd``: the combined map placed by
halftone + Lloyd instead of the paper's weighted draw).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from simlunar.errors import SimlunarError
from simlunar.planner import NelderMeadOptions, ScoreProtocol, fit_combination, score_combination
from simlunar.planner.combination import DEFAULT_FEATURES, DEFAULT_PROTOCOL
from simlunar.results.figures import load_results
from simlunar.results.store import UnitCache, atomic_write_bytes

__all__ = ["FIT_SEARCH", "main", "run_fit"]

#: the fit's search: shorter than :func:`fit_combination`'s default (40 iterations, 1 restart)
FIT_SEARCH = NelderMeadOptions(maxiter=40, restarts=1)


def _scenes(res: dict, seeds: list[int]) -> list[tuple]:
    cache = UnitCache(res["dir"])
    by_seed = {}
    for rec in res["units"]:
        s = (rec.get("sweep") or {}).get("seed", (rec.get("config") or {}).get("seed"))
        by_seed[int(s)] = rec
    missing = [s for s in seeds if s not in by_seed]
    if missing:
        raise ValueError(f"seeds {missing} are not units of {res['dir']} (has {sorted(by_seed)})")
    out = []
    for s in seeds:
        arr = cache.load_arrays(by_seed[s]["key"])
        if arr is None or "depth" not in arr or "image" not in arr:
            raise ValueError(
                f"{res['dir']}: unit of seed {s} has no cached guide image and depth "
                "(rerun its experiment into the folder)"
            )
        out.append((arr["depth"], arr["image"]))
    return out


def run_fit(
    out_dir: str | Path,
    *,
    train_seeds: list[int],
    test_seeds: list[int],
    features: tuple[str, ...] = DEFAULT_FEATURES,
    protocol: ScoreProtocol = DEFAULT_PROTOCOL,
    search: NelderMeadOptions = FIT_SEARCH,
    entropy_scale: str = "unit",
    rng: int = 0,
) -> dict:
    """Fit on the training seeds' units, score on the test seeds'; returns the report dict.

    ``protocol`` (densities, trials, metric) scores both the fit and the held-out seeds;
    ``search`` is the Nelder-Mead search of the fit (its ``maxiter`` and ``restarts``).
    """

    for name, v, least in (
        ("maxiter", search.maxiter, 1),
        ("restarts", search.restarts, 0),
        ("trials", protocol.trials, 1),
    ):
        if isinstance(v, bool) or int(v) != v or v < least:
            raise ValueError(f"--{name} must be an integer >= {least}, got {v}")
    res = load_results(out_dir)
    kind = ((res["config"] or {}).get("study") or {}).get("kind", "sampling")
    if kind != "sampling":
        raise ValueError(
            f"{out_dir}: holds a {kind} study; the fit reads the guide images and depths of a "
            "sampling experiment swept over seed (experiments/fit_combination.yaml)"
        )
    if set(train_seeds) & set(test_seeds):
        raise ValueError("train and test seeds must not overlap")
    train, test = _scenes(res, train_seeds), _scenes(res, test_seeds)
    fopts = {"entropy": {"scale": entropy_scale}}
    kw = dict(protocol=protocol, feature_opts=fopts)
    t = time.perf_counter()
    fit = fit_combination(train, features=features, rng=rng, search=search, **kw)
    fit_s = time.perf_counter() - t
    start = {f: 1.0 / len(features) for f in features}
    test_scores = {"fitted": score_combination(test, fit.coefficients, rng=rng + 1, **kw)}
    test_scores["equal weights"] = score_combination(test, start, rng=rng + 1, **kw)
    for f in features:
        test_scores[f] = score_combination(test, {f: 1.0}, rng=rng + 1, **kw)
    report = {
        "experiment": res["config"].get("name"),
        "train_seeds": list(train_seeds),
        "test_seeds": list(test_seeds),
        "features": list(features),
        "densities": list(protocol.densities),
        "trials": protocol.trials,
        "metric": protocol.metric,
        "placement": protocol.placement,
        "entropy_scale": entropy_scale,
        "coefficients": fit.coefficients,
        "train_score": fit.score,
        "train_score_start": fit.initial_score,
        "test_scores": test_scores,
        "nfev": fit.nfev,
        "fit_s": round(fit_s, 1),
    }
    out = Path(out_dir)
    stem = "fit" if protocol.placement == "random" else f"fit_{protocol.placement}"
    atomic_write_bytes(out / f"{stem}.json", json.dumps(report, indent=2).encode())
    atomic_write_bytes(out / f"{stem}.md", _markdown(report).encode())
    return report


_PLACEMENT = {"random": "weighted random draw (paper)", "lloyd": "halftone + Lloyd"}


def _markdown(r: dict) -> str:
    coefs = " | ".join(f"{v:.3f}" for v in r["coefficients"].values())
    lines = [
        f"### Fitted combination ({r['experiment']}, {r['metric'].upper()} score, eq. 4.3)",
        "",
        f"Train seeds {r['train_seeds']}, held-out seeds {r['test_seeds']}; densities "
        f"{', '.join(f'1/{round(1 / d)}' for d in r['densities'])}, {r['trials']} trials; "
        f"placement {_PLACEMENT[r.get('placement', 'random')]}; "
        f"Nelder-Mead, {r['nfev']} evaluations, {r['fit_s']} s.",
        "",
        "| " + " | ".join(r["coefficients"]) + " |",
        "|" + "---:|" * len(r["coefficients"]),
        f"| {coefs} |",
        "",
        f"Train score: {r['train_score']:.3f} (equal-weight start {r['train_score_start']:.3f}).",
        "",
        "| held-out | score |",
        "|---|---:|",
        *[f"| {k} | {v:.3f} |" for k, v in r["test_scores"].items()],
        "",
    ]
    return "\n".join(lines)


class _Parser(argparse.ArgumentParser):
    """Usage errors in one line, exit 2 (the CLI's promise)."""

    def error(self, message: str):
        self.exit(2, f"error: {self.prog}: {' '.join(message.split())} (see --help)\n")


def main(argv: list[str] | None = None) -> int:
    """Command line: ``python -m simlunar.pipeline.fit RESULTS --train-seeds ... --test-seeds ...``.

    Exit codes as ``simlunar``'s: 2 a user error, 3 a write refused, 130 Ctrl-C, each one line.
    """
    p = _Parser(prog="python -m simlunar.pipeline.fit", description=__doc__)
    p.add_argument("results", help="result folder of a sampling experiment swept over seed")
    p.add_argument("--train-seeds", type=int, nargs="+", required=True)
    p.add_argument("--test-seeds", type=int, nargs="+", required=True)
    p.add_argument("--maxiter", type=int, default=40, help="Nelder-Mead iterations per run")
    p.add_argument("--restarts", type=int, default=1)
    p.add_argument("--trials", type=int, default=2)
    p.add_argument(
        "--placement",
        choices=("random", "lloyd"),
        default="random",
        help="placement of the combined map: the paper's weighted random draw (default) or the "
        "halftone + Lloyd layout (deterministic: --trials 1 is enough)",
    )
    a = p.parse_args(argv)
    try:
        report = run_fit(
            a.results,
            train_seeds=a.train_seeds,
            test_seeds=a.test_seeds,
            protocol=ScoreProtocol(trials=a.trials, placement=a.placement),
            search=NelderMeadOptions(maxiter=a.maxiter, restarts=a.restarts),
        )
    except (FileNotFoundError, ValueError, SimlunarError) as e:
        print(f"error: {' '.join(str(e).split())}", file=sys.stderr)
        return 2
    except OSError as e:  # a write refused (disk full, read-only, permissions)
        print(f"error: {e.filename or a.results}: {e.strerror or e}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    try:
        print(_markdown(report))
    except BrokenPipeError:
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
