"""Captions of the landing-site figures (:mod:`simlunar.plotting.landing`): what each bar,
point and colour is, with the hazard sizes, slope and footprint of the study that ran."""

from __future__ import annotations

__all__ = ["landing_cost", "landing_hazards", "landing_recall"]


def landing_recall(study: dict, reconstruction: str) -> str:
    """Caption of ``landing_recall``."""
    land = study.get("landing") or {}
    sizes = ", ".join(f"{round(float(h) * 100)} cm" for h in land.get("rock_heights_m") or [])
    seeds = int(study.get("terrain_seeds", 1) or 1)
    return (
        f"Landing hazards found by each sensor and planner ({reconstruction} reconstruction), "
        f"one panel per sun elevation: recall of the rocks taller than {sizes} (rocks counted "
        f"as objects), recall of the slopes above {land.get('slope_deg', 5)} deg across a "
        f"{land.get('footprint_m', 4)} m footprint (pixels), and the false-safe rate (the "
        'chosen site called safe but unsafe in the truth; "no safe site" where a sensor and '
        "planner called no site safe on any seed). Black diamonds: the mean precision of the "
        "hazard under them (a high recall at a low precision is false alarms). Bars: mean over "
        f"{seeds} terrain seed(s); whiskers: 95 % bootstrap interval over seeds."
    )


def landing_cost(study: dict, reconstruction: str) -> str:
    """Caption of ``landing_cost``."""
    land = study.get("landing") or {}
    small = min((float(h) for h in land.get("rock_heights_m") or [0.15]), default=0.15)
    seeds = int(study.get("terrain_seeds", 1) or 1)
    return (
        f"What time and energy buy ({reconstruction} reconstruction): recall of the rocks taller "
        f"than {round(small * 100)} cm against the acquisition's scan time (left) and the laser "
        "energy it fired (right), both log scales, one row per sun elevation. Colour: the "
        "sensor; marker: the planner's strategy, its plans (a density, or fitted to a time or "
        "energy budget) joined in order of cost; dashed with open markers, the same plans' "
        "precision of those rocks (a recall bought with false alarms shows as one). Points: "
        "mean over "
        f"{seeds} terrain seed(s); whiskers: 95 % bootstrap interval over seeds."
    )


def landing_hazards(study: dict) -> str:
    """Caption of ``landing_hazards_unit<i>``."""
    land = study.get("landing") or {}
    big = max(float(h) for h in land.get("rock_heights_m") or [0.3])
    return (
        "The guide image, the true hazard map the site choice reads (rocks taller than "
        f"{round(big * 100)} cm above the median of a {land.get('footprint_m', 4)} m square, "
        f"or slopes above {land.get('slope_deg', 5)} deg across it) and each planner's and "
        "reconstruction's map (trial 0, largest density): black found, red missed, blue false "
        "alarm. Terrain seed 0 of each sweep point."
    )
