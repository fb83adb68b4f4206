"""Caption text for the figures a result folder holds (written to ``figures/captions.md``).

Each function returns one paragraph: what is plotted, the units, and what bands, bars and
colour scales mean, with the experiment's own numbers (trials, densities, units) filled in.
"""

from __future__ import annotations

from simlunar.metrics import METRIC_NAMES
from simlunar.plotting.style import METRIC_UNITS, axis_name, label

__all__ = [
    "Captions",
    "bit_errors",
    "error_vs_density",
    "headroom",
    "lidar_error",
    "panels",
    "reconstruction_panels",
    "reconstruction_saved",
    "samples_saved",
    "scanner_errors",
    "scanner_vs_sweep",
    "score_vs_sweep",
    "sparse_mesh",
]


class Captions(dict):
    """The captions of a folder's figures (``{stem: caption}``) and the figures not drawn
    with the reason of each (:attr:`not_drawn`, written to ``figures/not_drawn.md`` and shown
    by the report): a figure with nothing to show is left out, never drawn empty."""

    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self.not_drawn: dict[str, str] = {}

    def skip(self, stem: str, reason: str) -> None:
        """Record that figure ``stem`` is not drawn, and why (one sentence)."""
        self.not_drawn[stem] = reason


_METRIC_TEXT = {
    "mse": "mean squared depth error over all cells",
    "grad": "mean squared depth error weighted by the true depth-gradient magnitude (GRAD)",
    "sal": "mean squared depth error weighted by the guide image's Itti-Koch saliency (SAL)",
    "rmse": "root-mean-square depth error",
    "mae": "mean absolute depth error",
}


def _strategy_list(names) -> str:
    """Display labels joined by semicolons (labels such as "Wavelet, blue noise" hold commas)."""
    return "; ".join(label(s) for s in names)


def _metric(m: str) -> str:
    unit = METRIC_UNITS.get(m, "")
    return f"{_METRIC_TEXT.get(m, METRIC_NAMES.get(m, m))}{f', in {unit}' if unit else ''}"


def _recon_text(name: str) -> str:
    """A reconstruction's name as the captions write it (``linear`` is Delaunay-linear)."""
    return "Delaunay-linear" if name == "linear" else label(name)


def error_vs_density(
    metric: str,
    study: dict,
    n_panels: int,
    *,
    seeds: int = 1,
    reconstructions: list[str] | None = None,
) -> str:
    """Caption of ``error_vs_density_<metric>`` (``seeds``: terrain seeds pooled per panel;
    ``reconstructions``: the reconstructions drawn, one line style each when several)."""
    recons = list(reconstructions or ["linear"])
    trials = study.get("trials", 20)
    strategies = _strategy_list(study.get("strategies") or [])
    per = " One panel per scene or sweep point." if n_panels > 1 else ""
    ref = (
        " Random, the reference of every score, is dashed and drawn on top."
        if "random" in (study.get("strategies") or [])
        else ""
    )
    if seeds > 1:
        over = (
            f"mean over {seeds} terrain seeds × {trials} trials per density (every trial of "
            f"every terrain realisation of the panel's sweep point); shaded band: ±1 standard "
            f"deviation over those {seeds * trials} runs, so it holds the spread between "
            f"terrains as well as between trials"
        )
    else:
        over = (
            f"mean over {trials} trials per density; shaded band: ±1 standard deviation "
            f"over those trials (a fresh grid shift, random draw and noise per trial)"
        )
    if len(recons) > 1:
        which = (
            f"each reconstruction ({'; '.join(_recon_text(r) for r in recons)}) from the same "
            f"k range samples"
        )
        styles_text = (
            " Colour and marker name the planner, the line style the reconstruction (the "
            "legend lists both); every reconstruction of a planner reads the same plans."
        )
        ref = ref.replace(" is dashed and", " is")
    else:
        which = f"the {_recon_text(recons[0])} reconstruction from k range samples"
        styles_text = ""
    return (
        f"Reconstruction error against sampling density k/N (log-log; density falls to the "
        f"right, as in the paper's Fig. 3). y: {_metric(metric)} of {which} against the "
        f"full-resolution ground truth. "
        f"Lines: {over}, clipped below at half the smallest mean on the log axis. "
        f"Strategies: {strategies}.{styles_text}{ref}{per}"
    )


def panels(density_label: str, point: str, *, metres: bool = True) -> str:
    """Caption of ``panels_unit<i>`` (``metres``: axes in metres, a nadir orthographic view)."""
    at = f" at {density_label}" if density_label else ""
    scene = f" ({point})" if point else ""
    axes = (
        "Axes in metres on the ground (a pixel is one terrain cell). "
        if metres
        else "Axes in image pixels (a perspective view). "
    )
    return (
        f"Image-directed sampling of one scene{scene}. {axes}Top: the guide image (sensor "
        f"output, 0-1); its db2 wavelet detail-energy map (log10, dimensionless), the map the "
        f"Wavelet planner samples from; the Wavelet planner's samples{at} (red dots) on the "
        f"guide image. Bottom: the true depth from the camera and the Delaunay reconstruction "
        f"from those samples on one colour scale (m); the error reconstruction - truth (m) on "
        f"a symmetric scale clipped at the 99th percentile of |error|. Dashed: the convex hull "
        f"of the samples; outside it (bands along the borders) the reconstruction takes the "
        f"nearest sample's depth instead of interpolating, so the error grows there."
    )


def sparse_mesh(
    n_samples: int | None, rough: bool, *, threshold: float | None = None, light: str = "sun"
) -> str:
    """Caption of ``sparse_mesh_unit<i>`` (paper Fig. 4); ``light`` is the unit's light kind
    (what makes the terraces' steps dark depends on it)."""
    n = f"{n_samples} " if n_samples else ""
    thr = (
        f" Cells whose normalised energy is {threshold:g} or more keep the minimum roughness "
        f"(the threshold that keeps major features metric); the energy map is piecewise "
        f"constant over wavelet blocks, so the modulated render and the difference show "
        f"blocks."
        if rough and threshold
        else " The energy map is piecewise constant over wavelet blocks, so the modulated "
        "render and the difference show blocks."
        if rough
        else ""
    )
    diff = (
        "Top: the sparse mesh rendered with Oren-Nayar roughness modulated per cell by the "
        "wavelet energy, the sparse mesh with constant roughness, the full-resolution "
        "terrain. Below: the difference of the modulated render from the constant one (in "
        "units of the shared exposure, symmetric scale clipped at the 99th percentile of "
        f"|difference|, so a few extreme pixels do not flatten it) and the frequency (wavelet "
        f"energy) map, log10.{thr} "
        if rough
        else "The sparse mesh with constant roughness; the full-resolution terrain; the "
        "frequency (wavelet energy) map, log10. "
    )
    return (
        f"Rendering a terrain rebuilt from {n}wavelet-planned samples (paper Fig. 4). "
        f"{diff}All renders share one exposure (the 99.5th percentile of the full-resolution "
        f"render), so brightness differences are real. Dark wedges along the borders of the "
        f"sparse-mesh renders lie outside the samples' convex hull, where the mesh takes the "
        f"nearest sample's height (terraces with steps between them): {_STEPS.get(light, '')}"
    ).rstrip()


#: why the terraces' steps of a sparse mesh render dark, by light kind
_STEPS = {
    "sun": "steps facing away from the sun render dark, more so the lower the sun.",
    "camera": "under camera-centred light the steep steps are lit and seen at grazing angles, "
    "so they render dark whichever way they face.",
}


def score_vs_sweep(metric: str, path: str, study: dict, *, seeds: int = 1) -> str:
    """Caption of ``score_vs_<axis>_<metric>`` (ablations)."""
    trials = study.get("trials", 20)
    over = "terrain seeds" if seeds > 1 else "trials (one terrain seed)"
    return (
        f"{METRIC_NAMES.get(metric, metric)} score (paper eq. 4.3: the inverse-density-"
        f"weighted mean over densities of e_random / e_strategy, {trials} trials per density; "
        f"random = 1 by construction, dotted line; higher is better) against "
        f"{axis_name(path)} (sweep key `{path}`). Each point is one sweep point's score, its "
        f"error bar the 95 % interval of scores.md (paired bootstrap over {over}); a "
        f"categorical axis shows unconnected markers, offset side by side per strategy."
    )


def scanner_errors(
    metrics: list[str], n_units: int, *, n_min: int = 2, relative: bool = False
) -> str:
    """Caption of ``scanner_errors`` (section 5; ``n_min``: the fewest values of a bar)."""
    ms = "; ".join(f"{METRIC_NAMES.get(m, m)}: {_metric(m)}" for m in metrics)
    seeds = f" and {n_units} sweep points (seeds)" if n_units > 1 else ""
    spread = (
        "error bars: ±1 standard deviation over the same values (n in each tick label)"
        if n_min >= 2
        else "error bars where a bar pools 2 or more values (n in each tick label): ±1 "
        "standard deviation; a bar of one value has none"
    )
    rel = (
        " Bottom row: each scan's error divided by the gray-code scan's (dotted line at 1; the "
        "change in per cent above each bar), the comparison of the paper's section 5."
        if relative
        else ""
    )
    return (
        f"Structured-light scanner study: depth error of each scan mode / dot planner against "
        f"the ground truth on the guide grid ({ms}; axes in the unit that suits the values). "
        f"Bars: mean over all trials{seeds}; {spread}. Lower is better.{rel}"
    )


def scanner_vs_sweep(metrics: list[str], path: str, trials: int) -> str:
    """Caption of ``scanner_vs_<axis>`` (scanner ablations)."""
    ms = "; ".join(f"{METRIC_NAMES.get(m, m)}: {_metric(m)}" for m in metrics)
    spread = (
        f"mean over {trials} planner trials, error bars ±1 standard deviation over them"
        if trials > 1
        else "one planner trial per point"
    )
    return (
        f"Structured-light scanner study against {axis_name(path)} (sweep key `{path}`): depth "
        f"error of each scan mode / dot planner against the ground truth on the guide grid "
        f"({ms}; {spread}; log axes where the values span more than a factor of 20), and the "
        f"fraction of guide pixels the scan measured (last panel; the rest are filled from "
        f"their neighbours before scoring). Lower error is better."
    )


def bit_errors(n_units: int, all_zero: bool, n_bits: int = 0) -> str:
    """Caption of ``gray_code_bit_errors`` (with ``all_zero``: why no figure is drawn)."""
    over = f", mean over trials and {n_units} units" if n_units > 1 else ", mean over trials"
    if all_zero:
        return (
            f"Not drawn: all {n_bits} per-bit gray-code error rates are 0 or undefined (no "
            f"pixel near that bit's stripe edges), so no bit of any "
            f"pixel lit by the projector, near its true stripe edges, was decoded wrongly"
            f"{over}); results.csv holds them as ber_c<i> / ber_r<i>."
        )
    zero = ""
    return (
        f"Gray-code bit error rate per bit (0 = most significant; column bits and row bits): "
        f"the fraction of camera pixels lit by the projector, and at least one pixel from "
        f"that bit's true stripe edges, whose decoded bit differs from the truth{over}; "
        f"drawn per 100, thousand, million or billion pixels, whichever keeps the numbers "
        f"plain (the axis label says which).{zero}"
    )


def samples_saved(
    metric: str, references: list[str], point: str, *, reconstruction: str = "linear"
) -> str:
    """Caption of ``samples_saved`` (``samples_saved_point<i>``; ``reconstruction``: the one
    whose errors the planners are compared on)."""
    refs = " and ".join(label(r) for r in references)
    where = f" Sweep point: {point}." if point else ""
    return (
        f"Samples saved at equal error, one panel per reference ({refs}): for each strategy "
        f"and density, the number of reference samples that reach the strategy's "
        f"{_metric(metric)} (interpolated on the reference's log-log error-vs-samples curve), "
        f"divided by the strategy's own sample count; above 1 the strategy needs fewer "
        f"samples than the reference for the same error. Errors pool the terrain seeds and "
        f"trials. Hollow markers: outside the reference's measured range (extrapolated, "
        f"clipped to [1, N]); they are left out of the tables' geometric-mean summary. Every "
        f"error is of the {_recon_text(reconstruction)} reconstruction; a point is one "
        f"density, without an interval (reconstruction_saved* gives intervals over terrain "
        f"seeds).{where}"
    )


def reconstruction_saved(
    metric: str, path: str | None, seeds: int, reconstructions: list[str]
) -> str:
    """Caption of ``reconstruction_saved_vs_<axis>`` (``path``: the axis' readable name) and
    ``reconstruction_saved`` (``path`` None: one sweep point, the planners along x; else the
    sweep points)."""
    n = f"{seeds} terrain seed{'s' * (seeds != 1)}"
    interval = (
        "; error bars: its two-sided 95 % Student t interval over the seeds, in log space"
        if seeds > 1
        else "; one terrain seed gives no interval, so no error bar is drawn"
    )
    names = "; ".join(label(r) for r in reconstructions)
    against = f", against {path}" if path else ""
    layout = (
        "One panel per layout (strategy)."
        if path
        else "The planners along x (each one's layout is shared by every reconstruction), one "
        "marker per reconstruction."
    )
    return (
        f"Samples saved by each reconstruction ({names}) over Delaunay-linear on the same "
        f"layout{against}: per terrain seed, the samples linear needs to reach the "
        f"reconstruction's {_metric(metric)} (interpolated on linear's log-log "
        f"error-vs-samples curve) over the reconstruction's own, as a geometric mean over the "
        f"densities inside linear's measured range; then the geometric mean over the {n} "
        f"(marker){interval}. Above 1 (dotted) the reconstruction needs fewer samples than "
        f"linear for the same error. {layout} scores.md and reconstructions.csv hold the same "
        f"numbers."
    )


def reconstruction_panels(
    reconstructions: list[str],
    planner: str,
    k: int,
    density_label: str,
    point: str,
    *,
    metres: bool = True,
    frames: list[str] | None = None,
    light: str = "",
) -> str:
    """Caption of ``recon_panels_unit<i>`` (``frames``: the guide frames the image
    reconstructions could read, as the unit recorded them; ``light``: the guide image's light,
    as :func:`simlunar.plotting.style.point_title` writes it)."""
    at = f" ({density_label})" if density_label else ""
    scene = f" Scene: {point}." if point else ""
    axes = (
        "Axes in metres on the ground (a pixel is one terrain cell)."
        if metres
        else "Axes in image pixels (a perspective view)."
    )
    read = (
        f" The image reconstructions read the guide frames {', '.join(frames)}." if frames else ""
    )
    if light:
        read = f" Guide image: {light}.{read}"
    names = "; ".join(_recon_text(r) for r in reconstructions)
    return (
        f"The reconstructions of one plan, side by side: {k} samples{at} placed by the "
        f"study's {label(planner)} planner (bottom left, red dots on the guide image; the "
        f"samples are the true depth at those pixels, without range noise), reconstructed "
        f"by each configured reconstruction ({names}). Top: the true depth, then each "
        f"reconstruction, all on the true depth's colour scale (m). Bottom: each "
        f"reconstruction's error, reconstruction - truth (m), on one symmetric scale for all "
        f"of them, clipped at the 99th percentile of |error| over every map; the title gives "
        f"the RMS error over all cells. {axes}{read}{scene}"
    )


def _on(reconstruction: str | None) -> str:
    """The sentence naming the reconstruction a figure compares planners on (empty for a
    study of one reconstruction)."""
    if not reconstruction:
        return ""
    return f" Every error is of the {_recon_text(reconstruction)} reconstruction."


def headroom(metric: str, seeds: int, *, reconstruction: str | None = None) -> str:
    """Caption of ``headroom`` (``reconstruction``: the one the planners are compared on,
    named when the study has several)."""
    n = f"{seeds} terrain seed{'s' * (seeds != 1)}"
    return (
        f"Headroom captured at equal {_metric(metric)}, paired by terrain seed: for each "
        f"strategy, log(samples saved vs Uniform Lloyd) / log(the oracle's samples saved vs "
        f"Uniform Lloyd), the savings being geometric means over the densities inside the "
        f"reference's measured range. 1 (dotted) is the oracle's saving, 0 (solid) the uniform "
        f"layout's, below 0 worse than the uniform layout. Bars: the mean over the {n}; dots: "
        f"each seed. The oracle reads the true error and cannot be realised: it is a bound, not "
        f"a planner. One panel per sweep point and oracle; scores.md holds the same numbers "
        f"(mean [95 % t interval over the seeds] and the per-seed range).{_on(reconstruction)}"
    )


def saved_forest(metric: str, seeds: int, *, reconstruction: str | None = None) -> str:
    """Caption of ``samples_saved_forest`` (``reconstruction`` as :func:`headroom`)."""
    if seeds > 1:
        how = (
            f"Marker: the geometric mean over the {seeds} terrain seeds of each seed's samples "
            f"saved (itself the geometric mean over the densities inside the reference's "
            f"measured range); bar: its two-sided 95 % Student t interval in log space; grey "
            f"dots: each seed."
        )
    else:
        how = (
            "Marker: the samples saved on the one terrain seed (the geometric mean over the "
            "densities inside the reference's measured range); one seed gives no interval."
        )
    return (
        f"Samples saved at equal {_metric(metric)} against the image-free Uniform Lloyd layout "
        f"(dotted line at 1; right of it a planner needs fewer samples for the same error; log "
        f"axis). {how} Planners keep the style of every other figure (colour and marker per "
        f"planner); scores.md holds the same numbers in its headroom or paired samples-saved "
        f"table.{_on(reconstruction)}"
    )


def lidar_error(
    metric: str,
    study: dict,
    x: str,
    n_panels: int,
    *,
    seeds: int = 1,
    by: str | None = None,
    reconstructions: list[str] | None = None,
) -> str:
    """Caption of ``lidar_error_vs_<time|samples>_<metric>`` (``x``: ``seconds`` or
    ``samples``; ``reconstructions``: the ones drawn, a line style each, when several)."""
    sensor = str(study.get("sensor", "steered_beam")).replace("_", " ")
    trials = study.get("trials", 3)
    axis = (
        "the modelled acquisition time of the scan (s: steering moves, settling and pulses of "
        "a steered beam; frames x pulses / pulse rate of a flash)"
        if x == "seconds"
        else "the number of range samples measured (the planned pixels that returned; a "
        "flash: its receiver pixels)"
    )
    bars = (
        f"95 % percentile-bootstrap interval of the mean over the {seeds} terrain seeds "
        "(of each seed's mean over trials)"
        if seeds > 1
        else f"±1 standard deviation over the {trials} trials"
    )
    per = " One panel per sweep point." if n_panels > 1 else ""
    if by:
        per = f" Each point of a curve is one value of {by} (and density)."
    runs = f"{trials} trial{'s' if trials != 1 else ''}"
    recon = (
        f" Each planner has a curve per reconstruction of the same scans "
        f"({'; '.join(_recon_text(r) for r in reconstructions)}): colour and marker name the "
        f"planner, the line style the reconstruction."
        if reconstructions
        else ""
    )
    return (
        f"Image-directed LIDAR ({sensor}): error of the reconstructed guide-view depth "
        f"({_metric(metric)}) against {axis}, per planner, log-log; points: one per density, "
        f"mean over {runs}{f' on each of {seeds} terrain seeds' if seeds > 1 else ''}; error "
        f"bars: {bars}.{per}{recon}"
    )


def lidar_scan(study: dict, planners: list[str], *, densest: float | None = None) -> str:
    """Caption of ``lidar_scan_unit<i>``: one unit's example scans."""
    sensor = str(study.get("sensor", "steered_beam")).replace("_", " ")
    at = " at the study's largest density" if densest else ""
    return (
        f"One {sensor} scan per planner ({_strategy_list(planners)}): trial 0{at}. Left: the "
        "guide image the planner read and the true z-depth of the guide view (its range "
        "image). Top row: the planned beams on the guide image, joined in the order the "
        "sensor visited them (the line and dots run from dark, first, to bright, last: a "
        "steered beam's scan order, docs/lidar.md; a flash's frames one after the other, the "
        "dots of one frame, which fire together, in the plan's order). Bottom row: the z-depth each beam measured, on the colour scale of the "
        "true depth (its title: the share of beams that returned a range); a grey x is a beam "
        "that returned no range."
    )
