"""The rules a LIDAR study's options must meet together (planner labels, fits, motion,
time bins), checked on the schema's values so that a bad combination is one line naming its
key before anything runs. The option blocks themselves are :mod:`simlunar.config.lidar`."""

from __future__ import annotations

import math

from simlunar.config.lidar import MAX_BINS
from simlunar.study.reconstruction_spec import parse_reconstructions

__all__ = ["LIDAR_PLANNER_RULES", "check_lidar_study"]


#: what a LIDAR study asks of a planner label, by strategy: an oracle reads the true depth in
#: its planner step (a bound: its label starts "oracle", as in the sampling study); the
#: multi-round planner asks the LIDAR back between rounds (its samples must be the planned
#: cells; on a moving platform, a steered beam's)
LIDAR_PLANNER_RULES = {
    "oracle_greedy": "reads the true depth: a bound, not a planner",
    "oracle_hessian": "reads the true depth: a bound, not a planner",
    "sequential": "asks the LIDAR back between rounds",
}


def _check_planner_rules(study, i: int, label: str, name: str) -> None:
    """An oracle's label names it a bound; a multi-round planner needs a sensor that ranges
    the planned cells (on a moving platform: the steered beam), unfitted."""
    why = LIDAR_PLANNER_RULES.get(name)
    if why is None:
        return
    where = f"study.planners[{i}]"
    if name.startswith("oracle") and not label.startswith("oracle"):
        raise ValueError(
            f"{where}: the label {label!r} of {name!r} ({why}) must start with 'oracle', so "
            "every table shows it as a bound"
        )
    opts = study.planner_opts.get(label)
    recon = opts.oracle.reconstruction if opts is not None else "linear"
    labels = [spec.label for spec in parse_reconstructions(study.reconstructions)]
    if name == "oracle_greedy" and recon != "linear" and recon not in labels:
        raise ValueError(
            f"study.planner_opts.{label}.oracle.reconstruction: {recon!r} is not one of "
            f"study.reconstructions ({', '.join(labels)})"
        )
    if name == "sequential":
        if study.sensor == "flash":
            raise ValueError(
                f"{where}: {label!r} {why}, but a flash LIDAR measures its receiver pixels, "
                "not planned cells (use steered_beam or micromirror_flash)"
            )
        if opts is not None and opts.fit is not None:
            raise ValueError(f"study.planner_opts.{label}.fit: a multi-round planner is not fitted")


def check_lidar_study(study) -> None:
    """The rules the LIDAR library applies to its options, checked on the schema's values so
    a bad combination is one line naming its key before anything runs.

    ``study`` is a :class:`~simlunar.config.studies.LidarStudyCfg`.

    Raises
    ------
    ValueError
        ``study.<key>: ...`` naming the first offending key.
    """
    for i, label in enumerate(study.planners):
        opts = study.planner_opts.get(label)
        name = (opts.strategy if opts is not None else None) or label
        _check_planner_rules(study, i, label, name)
        fit = None if opts is None else opts.fit
        if fit is None:
            continue
        where = f"study.planner_opts.{label}.fit"
        if fit.kind == "receiver" and study.sensor != "micromirror_flash":
            raise ValueError(f"{where}: a receiver fit is for the micromirror_flash sensor")
        if fit.kind == "scan_time":
            ref = study.planner_opts.get(fit.reference)
            if fit.reference not in study.planners or (ref is not None and ref.fit is not None):
                raise ValueError(
                    f"{where}.reference: {fit.reference!r} must be an unfitted planner of "
                    f"study.planners ({', '.join(study.planners)})"
                )
            if study.sensor == "flash":
                raise ValueError(f"{where}: a flash's time is its frames, not a tour")
        expert = any(getattr(study.options.detector, f"expert_{k}", None) is not None
                     for k in ("signal_photons", "background_photons_per_s"))  # fmt: skip
        if fit.kind == "budget" and fit.budget_j is not None and expert:
            # simlunar.sensors' scan_energy_j refuses it in the unit, after the render
            raise ValueError(
                f"{where}.budget_j: an energy budget needs the instrument's pulse energy, and "
                "the expert photon scales (study.options.detector.expert_*) name none"
            )
    o = study.options
    apd = o.detector.apd
    if apd is not None and apd.agc_target is not None and study.sensor != "flash":
        # simlunar.lidar.scan.scan_beams and read_frame refuse it after the render
        raise ValueError(
            f"study.options.detector.apd.agc_target: the pulse-energy control is a flash "
            f"frame's; a {study.sensor} has none (leave agc_target unset)"
        )
    if study.sensor == "steered_beam":
        sb = o.steered_beam
        # simlunar.lidar.scan.SteeredBeamOptions: window_m > 2 margin_m >= 0 (each
        # batch's window holds the ray-cast ranges with the margin on both sides)
        if not sb.window_m > 2 * o.margin_m:
            raise ValueError(
                f"study.options.margin_m: {o.margin_m:g} m leaves no range in the "
                f"{sb.window_m:g} m window of a rendered batch (steered_beam.window_m must "
                f"exceed 2 x margin_m = {2 * o.margin_m:g} m)"
            )
        bins = math.ceil(sb.window_m / o.bin_range_m)
        if bins > MAX_BINS:
            raise ValueError(
                f"study.options.bin_range_m: {o.bin_range_m:g} m makes {bins:.3g} time bins "
                f"of the {sb.window_m:g} m window (at most {MAX_BINS})"
            )
    fwhm_m = o.pulse.fwhm_ns * 1e-9 * 299_792_458.0 / 2  # the pulse's width in range
    if fwhm_m / o.bin_range_m > MAX_BINS:
        raise ValueError(
            f"study.options.pulse.fwhm_ns: a {o.pulse.fwhm_ns:g} ns pulse spans "
            f"{fwhm_m / o.bin_range_m:.3g} time bins of {o.bin_range_m:g} m (at most {MAX_BINS})"
        )
