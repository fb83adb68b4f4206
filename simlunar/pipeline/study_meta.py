"""The study part of a unit's record: its scores as plain numbers and the meta a sampling study
adds (sensor rounds of multi-round planners, the other reconstructions' scores and the
diagnostics each reported), each a mean over trials per density."""

from __future__ import annotations

import numpy as np

from simlunar.metrics import score as eq43_score

__all__ = ["plain_scores", "reconstruction_meta", "rounds_meta", "trial_means"]


def rounds_meta(study) -> dict:
    """Sensor rounds of each multi-round label (each round costs sensor time): mean over
    trials per density, densities in the study's order; nothing for one-shot studies."""
    if not study.rounds:
        return {}
    return {"rounds": {s: r.mean(axis=1).tolist() for s, r in study.rounds.items()}}


def reconstruction_meta(study) -> dict:
    """With reconstructions besides the first: each one's eq. 4.3 scores (the record's
    ``scores`` are the first's) and the diagnostics each reported (e.g. ``shading_share``),
    mean over trials per density (densities in the study's order); nothing for ``linear``
    alone, so its records are as before."""
    out: dict = {}
    others = study.reconstructions[1:]
    if others and study.reference in study.strategies:
        out["reconstruction_scores"] = {
            r: {
                m: {
                    s: float(v)
                    for s, v in eq43_score(
                        study.errors(m, r), study.densities, reference=study.reference
                    ).items()
                }
                for m in study.metrics
            }
            for r in others
        }
    if study.info:
        out["reconstruction_info"] = {
            r: {s: {k: trial_means(v) for k, v in keys.items()} for s, keys in by.items()}
            for r, by in study.info.items()
        }
    return out


def trial_means(v: np.ndarray) -> list:
    """Mean over trials (axis 1) of the finite values per density; None where there is none
    (a reconstruction that reported the key on no trial of that density)."""
    ok = np.isfinite(v)
    n = ok.sum(axis=1)
    sums = np.where(ok, v, 0.0).sum(axis=1)
    return [float(s / c) if c else None for s, c in zip(sums, n)]


def plain_scores(scores) -> dict:
    """Scores as {metric: {strategy: float}}."""
    return {str(m): {str(s): float(v) for s, v in by.items()} for m, by in dict(scores).items()}
