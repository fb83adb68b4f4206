"""One style (colour, marker, display label) per strategy, variant, scan mode and planner.

Figures and tables look names up here, so a strategy has the same colour in every figure and
the same label in a figure legend as in a table. The registry holds the five strategies of the
paper, simlunar's other strategies, the labelled variants the shipped experiments define
(``wavelet_bn``, ``wavelet_bn_mix``, ``fitted_combination``) and the scanner's modes.

A name the registry does not know (a new ``strategy_options`` label) gets the label
``name.replace("_", " ").capitalize()`` and a colour from :data:`SPARE_COLOURS` chosen by a
hash of the name: the same in every figure and every run, and never a registered colour.
:func:`styles` resolves hash collisions within one figure so every curve stays distinguishable.

This module does not import matplotlib: tables (plain text) use it too.
"""

from __future__ import annotations

import zlib
from collections.abc import Iterable
from dataclasses import dataclass

from simlunar.metrics import METRIC_NAMES, METRIC_UNITS  # METRIC_UNITS: re-exported
from simlunar.render.materials import BSDFS
from simlunar.scanner.codings import CODINGS


@dataclass(frozen=True)
class Style:
    """How one strategy / variant / mode is drawn and named.

    Attributes
    ----------
    colour : str
        Matplotlib colour (hex).
    marker : str
        Matplotlib marker.
    label : str
        Display label for legends, axis ticks and table headers.
    linestyle : str or tuple
        Matplotlib line style, by how the planner places its samples (:data:`PLACEMENT_LINES`):
        hue names the map (reds: wavelet, purples: learned, greens: multi-round), line style
        and marker tell the placement apart, so curves stay distinct in greyscale and for
        colour-blind readers.
    """

    colour: str
    marker: str
    label: str
    linestyle: str | tuple = "-"


#: line style per placement: the paper's weighted random draw (and the grid) solid, the
#: halftone + Lloyd layouts dash-dotted, multi-round sampling dash-dot-dotted, the
#: truth-reading oracles dotted. Random, the reference of every score, is drawn dashed by the
#: error figure itself.
PLACEMENT_LINES = {
    "draw": "-",
    "lloyd": "-.",
    "sequential": (0, (3, 1, 1, 1, 1, 1)),
    "oracle": ":",
}


#: registered styles (strategies of the paper first, then simlunar's, variants, scan modes)
REGISTRY: dict[str, Style] = {
    # the paper's five strategies (Tables 1 and 2)
    "random": Style("#7f7f7f", "o", "Random"),
    "grid": Style("#1f77b4", "s", "Grid"),
    "gradient": Style("#ff7f0e", "^", "Gradient"),
    "entropy": Style("#2ca02c", "v", "Entropy"),
    "wavelet": Style("#d62728", "D", "Wavelet"),
    # simlunar's other strategies
    "saliency": Style("#9467bd", "P", "Saliency"),
    "combination": Style("#8c564b", "X", "Combination"),
    # image-free and image-directed layouts with halftone + Lloyd placement, multi-round
    # planning and the truth-reading bounds (oracle labels start "Oracle")
    # (the same map keeps its hue; the Lloyd placement gets its own marker and line style)
    "lloyd_uniform": Style("#000000", "8", "Uniform Lloyd", PLACEMENT_LINES["lloyd"]),
    "wavelet_lloyd": Style("#b2182b", "h", "Wavelet, Lloyd", PLACEMENT_LINES["lloyd"]),
    "learned": Style("#542788", "P", "Learned"),
    "learned_lloyd": Style("#8073ac", "p", "Learned, Lloyd", PLACEMENT_LINES["lloyd"]),
    "sequential": Style("#1b7837", ">", "Sequential", PLACEMENT_LINES["sequential"]),
    "sequential_wavelet": Style(
        "#5aae61", ">", "Sequential, wavelet prior", PLACEMENT_LINES["sequential"]
    ),
    "sequential_learned": Style(
        "#a6dba0", "<", "Sequential, learned prior", PLACEMENT_LINES["sequential"]
    ),
    "oracle_greedy": Style("#fdb863", "*", "Oracle greedy (true error)", PLACEMENT_LINES["oracle"]),
    "oracle_hessian": Style(
        "#e08214", "*", "Oracle Hessian (true depth)", PLACEMENT_LINES["oracle"]
    ),
    # labelled variants of the shipped experiments
    # a hue far from Wavelet's red (pink read as a second red beside it)
    "wavelet_bn": Style("#6a3d9a", "d", "Wavelet, blue noise"),
    "wavelet_bn_mix": Style("#17becf", "h", "Wavelet, blue noise + uniform"),
    "fitted_combination": Style("#bcbd22", "*", "Fitted combination"),
    # the scanner's scan-ranking rescan planner
    "low_contrast": Style("#252525", "*", "Low contrast"),
    # scanner modes (section 5); each full-field coding is a mode too (its style is its
    # registry entry's, added below)
    "ambiguity_enhancement": Style("#637939", "s", "Ambiguity enhancement"),
    "data_reduction": Style("#843c39", "^", "Data reduction"),
}

REGISTRY.update(
    {n: Style(*e.meta["style"], e.meta["label"]) for n, e in CODINGS.items() if "style" in e.meta}
)


def reference_mode(entries: Iterable[dict]) -> str | None:
    """The scan every other scan of a scanner study is compared with: the mode of the first
    entry without a planner (a full-field coding's own scan, the gray code in the paper), or
    None."""
    return next((e["mode"] for e in entries if e.get("mode") and not e.get("planner")), None)


#: colours for names the registry does not know (none of them is registered)
SPARE_COLOURS = (
    "#aec7e8",
    "#ffbb78",
    "#98df8a",
    "#ff9896",
    "#c5b0d5",
    "#c49c94",
    "#f7b6d2",
    "#dbdb8d",
    "#9edae5",
    "#5254a3",
    "#8ca252",
    "#bd9e39",
    "#ad494a",
    "#a55194",
    "#6b6ecf",
    "#e7ba52",
)
SPARE_MARKERS = ("o", "s", "^", "v", "D", "P", "X", "h")


#: display labels of other names shown on axes (sweep categories: BSDFs, lights)
PLAIN_LABELS = {
    **{n: e.meta["label"] for n, e in BSDFS.items()},  # the BSDF registry's labels
    "sun": "Sun",
    "camera": "Camera-centred light",
}


def label(name: str) -> str:
    """Display label of a strategy / variant / mode / planner name (tables and figures).

    Unknown names: underscores become spaces, first letter capitalised (``my_var`` ->
    ``"My var"``).
    """
    s = REGISTRY.get(name)
    if s is not None:
        return s.label
    if name in PLAIN_LABELS:
        return PLAIN_LABELS[name]
    return str(name).replace("_", " ").capitalize()


def style(name: str) -> Style:
    """The style of ``name``; unknown names get a spare colour chosen by a hash of the name."""
    s = REGISTRY.get(name)
    if s is not None:
        return s
    h = zlib.crc32(str(name).encode())
    return Style(
        SPARE_COLOURS[h % len(SPARE_COLOURS)], SPARE_MARKERS[h % len(SPARE_MARKERS)], label(name)
    )


def styles(names: Iterable[str]) -> dict[str, Style]:
    """Styles of several names drawn together, with pairwise distinct colours.

    Registered names keep their colour; an unknown name whose hashed spare colour is taken by
    an earlier name moves to the next free spare colour (deterministic for a given list).
    """
    out: dict[str, Style] = {}
    used: set[str] = set()
    names = list(dict.fromkeys(names))
    for n in names:  # registered first, so they never move
        if n in REGISTRY:
            out[n] = REGISTRY[n]
            used.add(REGISTRY[n].colour)
    for n in names:
        if n in out:
            continue
        s = style(n)
        i = SPARE_COLOURS.index(s.colour)
        for step in range(len(SPARE_COLOURS)):
            c = SPARE_COLOURS[(i + step) % len(SPARE_COLOURS)]
            if c not in used:
                s = Style(c, s.marker, s.label, s.linestyle)
                break
        used.add(s.colour)
        out[n] = s
    return {n: out[n] for n in names}


def pair_label(mode: str, planner: str | None) -> str:
    """Label of a scanner row: ``"Ambiguity enhancement / Wavelet"`` (mode alone without planner)."""
    return f"{label(mode)} / {label(planner)}" if planner else label(mode)


#: readable names of sweep axes (config paths), for axis labels
AXIS_NAMES = {
    "render.light": "light source",
    "render.light.elevation_deg": "sun elevation (deg)",
    "render.light.azimuth_deg": "sun azimuth (deg)",
    "render.light.irradiance": "sun irradiance (W/m²)",
    "study.options.gray_opts.black_threshold": "gray-code validity threshold",
    "render.bsdf": "reflectance model (BSDF)",
    "render.bsdf.albedo": "albedo",
    "render.sensor.read_noise_e": "sensor read noise (e⁻)",
    "render.sensor.full_well_e": "sensor full well (e⁻)",
    "terrain.preset": "terrain preset",
    "terrain.albedo": "terrain albedo",
    "terrain.overrides.fractal.rms_m": "fractal roughness RMS (m)",
    "terrain.seed": "terrain seed",
    "seed": "seed",
}

_UNIT_SUFFIXES = {"_deg": "deg", "_m": "m", "_e": "e⁻", "_px": "px", "_s": "s"}


def metric_axis(metric: str, *, what: str = "error", unit: str | None = None) -> str:
    """Axis label of an error metric with its unit, e.g. ``"MSE error (m²)"`` (``unit``
    replaces the SI unit, e.g. ``"mm²"`` for values scaled by 1e6)."""

    name = METRIC_NAMES.get(metric, metric)
    unit = unit or METRIC_UNITS.get(metric)
    return f"{name} {what} ({unit})" if unit else f"{name} {what}"


def axis_name(path: str) -> str:
    """Readable axis label of a sweep path (``render.light.elevation_deg`` -> ``"sun elevation
    (deg)"``); unknown paths: the last key, its unit suffix as ``(unit)``."""
    if path in AXIS_NAMES:
        return AXIS_NAMES[path]
    key = str(path).rsplit(".", 1)[-1]
    for suffix, unit in _UNIT_SUFFIXES.items():
        if key.endswith(suffix):
            return f"{key[: -len(suffix)].replace('_', ' ')} ({unit})"
    return key.replace("_", " ")


def _name_and_unit(path: str) -> tuple[str, str]:
    """``("sun elevation", "deg")`` of a sweep path (unit "" when it has none)."""
    text = axis_name(path)
    if text.endswith(")") and " (" in text:
        name, _, unit = text[:-1].rpartition(" (")
        if " " not in unit or unit in ("W/m²",):
            return name, unit
    return text, ""


def _with_unit(value, unit: str) -> str:
    v = f"{value:g}" if isinstance(value, float) else str(value)
    if unit == "deg":
        return f"{v}°"
    return f"{v} {unit}" if unit else v


def _model_text(value: dict) -> str:
    """``{"kind": "sun", "elevation_deg": 30}`` -> ``"Sun (elevation 30°)"``."""
    parts = []
    for k, v in value.items():
        if k == "kind" or v is None or isinstance(v, (dict, list)):
            continue
        unit = ""
        for suffix, u in _UNIT_SUFFIXES.items():
            if k.endswith(suffix):
                k, unit = k[: -len(suffix)], u
                break
        parts.append(f"{k.replace('_', ' ')} {_with_unit(v, unit)}")
    head = label(str(value.get("kind", "")))
    return f"{head} ({', '.join(parts)})" if parts else head


def point_title(sweep: dict) -> str:
    """Title of a sweep point in one style for every figure: the axis's readable name, then
    the value with its unit (``"sun elevation: 5°"``); a model by its registry label and
    parameters (``"light source: Sun (elevation 30°, azimuth 135°)"``); null as the preset's
    default. Axes joined by ``"; "``."""
    parts = []
    for path, v in sweep.items():
        name, unit = _name_and_unit(path)
        if isinstance(v, dict):
            text = _model_text(v)
        elif v is None:
            text = "preset default"
        elif isinstance(v, str):
            text = label(v)
        elif isinstance(v, bool):
            text = "yes" if v else "no"
        else:
            text = _with_unit(v, unit)
        parts.append(f"{name}: {text}")
    return "; ".join(parts)


__all__ = [
    "AXIS_NAMES",
    "METRIC_UNITS",
    "PLAIN_LABELS",
    "REGISTRY",
    "SPARE_COLOURS",
    "SPARE_MARKERS",
    "Style",
    "axis_name",
    "label",
    "metric_axis",
    "pair_label",
    "point_title",
    "style",
    "styles",
]
