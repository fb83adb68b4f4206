"""The figures of a scanner-study result folder: errors per scan mode / planner and their
ratio to the gray-code scan, or errors against the swept value of an ablation, and the
gray-code bit error rates (only when some bit was decoded wrongly)."""

from __future__ import annotations

import numpy as np

from simlunar.plotting import figures as F
from simlunar.plotting.style import axis_name, label, reference_mode
from simlunar.results import captions as captions_text
from simlunar.results.aggregate import (
    SEED_AXES,
    first_reconstruction_rows,
    reconstruction_names,
    row_reconstruction,
    sweep_value,
)

__all__ = ["scanner_figures"]


def _scanner_pooled(rows: list[dict], metrics: list[str]) -> list[dict]:
    """Mean, s.d. and count of each metric per (mode, planner) over all units and trials."""
    groups: dict[tuple, dict[str, list[float]]] = {}
    for r in rows:
        key = (r["mode"], r.get("planner") or "")
        groups.setdefault(key, {}).setdefault(r["metric"], []).append(float(r["value"]))
    out = []
    for (mode, planner), vals in groups.items():
        e = {"mode": mode, "planner": planner}
        for m in metrics:
            v = np.asarray(vals.get(m, []), float)
            v = v[np.isfinite(v)]
            e[m] = float(v.mean()) if v.size else None
            e[f"{m}_sd"] = float(v.std(ddof=1)) if v.size > 1 else None
            e["n"] = int(v.size)
        out.append(e)
    return out


def _ambient_axis(rows: list[dict], units: list[dict], path: str):
    """``(factor, label)`` of a sun-to-projector axis when every unit of a one-axis sweep is a
    daylight scan whose ``ambient_ratio`` is proportional to the swept value (the sun's
    irradiance), else None."""
    ratio = {str(r.get("unit")): float(r["value"]) for r in rows if r["metric"] == "ambient_ratio"}
    k = []
    for rec in units:
        x, v = rec["sweep"].get(path), ratio.get(str(rec.get("index", 0)))
        if v is None or not isinstance(x, (int, float)) or isinstance(x, bool) or x <= 0:
            return None
        k.append(v / x)
    if not k or max(k) - min(k) > 1e-3 * max(k) or not max(k) > 0:
        return None
    return float(sum(k) / len(k)), "sun / projector white, as the camera sees it"


def scanner_figures(res: dict, emit, captions: dict) -> None:
    """Draw the scanner figures through ``emit(fig, stem)``; captions into ``captions``: the
    errors of the first configured reconstruction's rows (linear's by default) and, with
    several reconstructions, the same figure of each other one (``<stem>_<reconstruction>``,
    its title naming it)."""
    rows = first_reconstruction_rows(res)
    names = reconstruction_names(res["config"].get("study") or {})
    all_rows = res["rows"]
    res = {**res, "rows": rows}
    _error_figures(res, rows, emit, captions, "", names[0] if len(names) > 1 else None)
    for name in names[1:]:
        mine = [r for r in all_rows if row_reconstruction(r) == name]
        if mine:
            _error_figures(res, mine, emit, captions, f"_{name}", name)
    n_units = len({str(r.get("unit", "0")) for r in rows})
    ber = sorted(
        {r["metric"] for r in rows if r["metric"].startswith("ber_")},
        key=lambda n: (n[4], int(n[5:])),
    )
    if ber:
        vals = {n: np.mean([float(r["value"]) for r in rows if r["metric"] == n]) for n in ber}
        # a NaN rate (no pixel near that bit's stripe edges) is no error either
        all_zero = not any(np.isfinite(v) and v > 0 for v in vals.values())
        text = captions_text.bit_errors(n_units, all_zero, len(ber))
        if all_zero and hasattr(captions, "skip"):  # the report lists it among "Not drawn"
            captions.skip("gray_code_bit_errors", text.removeprefix("Not drawn: "))
        else:
            captions["gray_code_bit_errors"] = text
        if not all_zero:  # 14 zero rates are a sentence (the caption), not a figure
            fig, _ = F.bit_error_rates(vals)
            emit(fig, "gray_code_bit_errors")


def _error_figures(res: dict, rows: list, emit, captions: dict, suffix: str, recon) -> None:
    """``scanner_vs_<axis>`` or ``scanner_errors`` (``+ suffix``) of ``rows``; ``recon``
    names their reconstruction in the title and caption (None: the study has one)."""
    cfg = res["config"]
    metrics = list(cfg["study"].get("metrics") or [])
    sweep = cfg.get("sweep") or {}
    units = res["units"]
    n_units = len({str(r.get("unit", "0")) for r in rows})
    if len(sweep) == 1 and next(iter(sweep)) not in SEED_AXES and len(units) > 1:
        # an ablation: the errors against the swept value (pooling across it would mix
        # errors of different conditions into one bar)
        (path,) = sweep
        shown = [*metrics, "valid_fraction"]
        by_unit: dict[str, list[dict]] = {}
        for r in rows:
            by_unit.setdefault(str(r.get("unit")), []).append(r)
        points = [
            (
                sweep_value(rec, path),
                _scanner_pooled(by_unit.get(str(rec.get("index", 0)), []), shown),
            )
            for rec in units
        ]
        fig, axes = F.panel_grid(len(shown), height=2.8)
        secondary = _ambient_axis(rows, units, path)
        for ax, m in zip(axes, shown):
            F.scanner_vs_sweep(
                points, metric=m, axis_label=axis_name(path), ax=ax, secondary=secondary
            )
        F.shared_legend(fig, axes, prune_labels=False)
        axis = path.rsplit(".", 1)[-1]
        stem = f"scanner_vs_{axis}{suffix}"
        _title(fig, recon)
        emit(fig, stem)
        captions[stem] = captions_text.scanner_vs_sweep(
            metrics, path, int(cfg["study"].get("trials", 1))
        ) + _named(recon)
    else:
        summary = _scanner_pooled(rows, metrics)
        relative = reference_mode(summary) is not None and len(summary) > 1
        fig, axes = F.panel_grid(
            len(metrics) * (2 if relative else 1), ncols=len(metrics), height=2.7
        )
        for ax, m in zip(axes, metrics):
            F.scanner_bars(summary, metric=m, ax=ax)
        if relative:
            for ax, m in zip(axes[len(metrics) :], metrics):
                F.scanner_relative_bars(summary, metric=m, ax=ax)
        _title(fig, recon)
        emit(fig, f"scanner_errors{suffix}")
        captions[f"scanner_errors{suffix}"] = captions_text.scanner_errors(
            metrics, n_units, n_min=min(e["n"] for e in summary), relative=relative
        ) + _named(recon)


def _title(fig, recon) -> None:
    if recon:
        fig.suptitle(f"reconstruction: {label(recon)}", fontsize=8)


def _named(recon) -> str:
    return f" Depths of the {label(recon)} reconstruction of every scan." if recon else ""
