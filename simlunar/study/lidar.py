"""The LIDAR study: the study protocol with a time-of-flight sensor, scored at equal scan time.

For every planner, sample budget (a density k / N of guide pixels) and trial, the planner picks
guide pixels from the guide image, a LIDAR of :mod:`simlunar.sensors.lidar` measures them (a
steered beam ranges them in a time-optimised order; a micromirror flash lights them; a flash
LIDAR directs its zoomed revisits at the sub-fields holding most of them), the protocol
(:mod:`simlunar.study.protocol`) reconstructs the guide-view depth and scores it. Every row
carries the acquisition's modelled ``seconds`` and ``frames`` beside its sample count, so
error can be read against scan time as well as against samples. A sensor that needs no plan (a
flash LIDAR without revisits) runs once per trial under the planner label ``"none"``.

Every planner of the sampling study runs (:mod:`simlunar.study.lidar_planners`): the image
strategies, the oracles (bounds: they read the true depth in the planner step, never through
the sensor) and multi-round planning (each round measured by the LIDAR; ``seconds`` counts
every round and the re-pointing between them, so equal-scan-time comparisons are fair).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from simlunar.features import check_image
from simlunar.metrics import METRICS
from simlunar.metrics.hazard import HazardOptions, detection_scores, hazard_map
from simlunar.metrics.landing import LandingOptions, landing_scores
from simlunar.metrics.safe_site import SiteOptions, safe_site_scores
from simlunar.planner import DEFAULT_PLANNER, MEASURING, STRATEGIES
from simlunar.progress import stage
from simlunar.reconstruction import Guide
from simlunar.registry import Options, option
from simlunar.sensors import SENSORS
from simlunar.sensors.base import Acquisition
from simlunar.sensors.lidar import LidarScene
from simlunar.study.depth_scores import score_depth
from simlunar.study.lidar_planners import FITS, SensorFit, lidar_planners
from simlunar.study.protocol import (
    DEFAULT_RECONSTRUCTION,
    Trials,
    light_outcome,
    outcome_rows,
    reconstruction_options,
    run_protocol,
)
from simlunar.study.sampling import _seeds, sample_count
from simlunar.study.steps import ProtocolSteps, Steps

__all__ = [
    "FITS",
    "LIDARS",
    "NO_PLAN",
    "LidarStudyOptions",
    "LidarStudyResult",
    "SensorFit",
    "beam_table",
    "run_lidar_study",
    "time_table",
]

#: the planner label of a sensor that needs no plan
NO_PLAN = "none"
#: the LIDAR sensors of :data:`simlunar.sensors.SENSORS`
LIDARS = ("steered_beam", "flash", "micromirror_flash")


@dataclass(frozen=True)
class LidarStudyOptions(Options):
    """What a LIDAR study runs."""

    sensor: str = option("steered_beam", doc="a LIDAR of simlunar.sensors.SENSORS", choices=LIDARS)
    sensor_options: object = option(
        None, doc="options object of that sensor, or None (its defaults)"
    )
    planners: Sequence[str] = option(
        (DEFAULT_PLANNER, "random", "grid"),
        doc="planner labels: strategy names of simlunar.planner.STRATEGIES (from the guide "
        "image; an oracle_* reads the guide view's true depth in its planner step: a bound, its "
        "label starts oracle), sequential (multi-round: the LIDAR measures each round, "
        "simlunar.study.lidar_planners.LidarRounds), or labels whose strategy strategies names",
    )
    densities: Sequence[float] = option(
        (1 / 64, 1 / 256), doc="planned pixels k / N of the guide view, each in (0, 1]"
    )
    trials: int = option(3, doc="planner draws and photon noise per (planner, density)", ge=1)
    metrics: Sequence[str] = option(
        ("mse", "grad"),
        doc="names of simlunar.metrics.METRICS (against the guide view's true depth)",
    )
    planner_opts: Mapping[str, Mapping] = option(
        doc="per planner options of simlunar.planner.plan (feature_opts included; an "
        "oracle_greedy's reconstruction: a label of reconstructions whose true error it reads; "
        "sequential's {sequential: SequentialOptions, prior: map name or None, feature_opts: "
        "...})",
        default_factory=dict,
    )
    hazard: HazardOptions | None = option(
        None,
        doc="also score hazard detection (hazard_precision, hazard_recall) of the "
        "reconstruction against the true depth's hazards",
    )
    outside: str = option("nearest", doc="policy of linear outside the measured cells' hull")
    reconstructions: Mapping | Sequence = option(
        (DEFAULT_RECONSTRUCTION,),
        doc="reconstructions of simlunar.reconstruction.RECONSTRUCTIONS run on every acquisition "
        "(a mapping name -> options, or names; a guided one reads the guide camera's image)",
    )
    strategies: Mapping[str, str] = option(
        doc="the strategy of a planner label that is not itself a strategy name",
        default_factory=dict,
    )
    fits: Mapping[str, SensorFit] = option(
        doc="labels fitted to the sensor (scan time or receiver pixels)", default_factory=dict
    )
    safe_site: SiteOptions | None = option(
        None,
        doc="also score whether the landing site chosen from the reconstruction is truly safe "
        "(safe_site, safe_site_precision, safe_sites_available; simlunar.metrics.safe_site)",
    )
    landing: LandingOptions | None = option(
        None,
        doc="also score the landing site per hazard size: rock and slope recall / precision, "
        "false_safe_site, safe_site_called, height_rms, slope_rms_deg "
        "(simlunar.metrics.landing)",
    )

    def __post_init__(self):
        super().__post_init__()
        reconstruction_options(self.reconstructions, outside=self.outside)
        opts_cls = SENSORS[self.sensor][1]
        if self.sensor_options is not None and not isinstance(self.sensor_options, opts_cls):
            raise ValueError(
                f"sensor_options of {self.sensor!r} must be {opts_cls.__name__}, "
                f"got {type(self.sensor_options).__name__}"
            )
        bad = [m for m in self.metrics if m not in METRICS]
        if bad:
            raise ValueError(f"unknown metric {bad[0]!r}; valid: {', '.join(METRICS)}")
        valid = (*STRATEGIES, *MEASURING)
        bad = [p for p in self.planners if self.strategies.get(p, p) not in valid]
        if bad or not self.planners:
            raise ValueError(f"unknown planner {bad}; valid: {', '.join(valid)}")
        for label, fit in self.fits.items():
            if label not in self.planners:
                raise ValueError(f"fits for {label!r}, not a planner of the study")
            if fit.kind == "scan_time" and (
                fit.reference not in self.planners or fit.reference in self.fits
            ):
                raise ValueError(
                    f"fits[{label!r}]: reference {fit.reference!r} must be an unfitted planner "
                    "of the study"
                )
            if self.strategies.get(label, label) in MEASURING:
                raise ValueError(f"fits[{label!r}]: a multi-round planner is not fitted")
            if fit.kind == "receiver" and self.sensor != "micromirror_flash":
                raise ValueError(f"fits[{label!r}]: a receiver fit is for the micromirror flash")
        if not self.densities or not all(0 < d <= 1 for d in self.densities):
            raise ValueError(f"densities must be in (0, 1], got {list(self.densities)}")
        stray = sorted(set(self.planner_opts) - set(self.planners))
        if stray:
            raise ValueError(f"planner_opts for planners not in the study: {stray}")


@dataclass(frozen=True, eq=False)
class LidarStudyResult:
    """Tidy rows and one example acquisition per planner.

    Attributes
    ----------
    rows : list of dict
        Keys: planner, reconstruction, density, k (planned pixels), trial, metric, value,
        seconds, frames, samples (range samples measured; a flash's receiver pixels) and, for
        a reconstruction that read guide frames, guide_frames and exposures. Metrics: the requested
        ones, ``valid_fraction`` (measured over planned samples; over receiver pixels for a
        flash) and, with hazards, ``hazard_precision`` / ``hazard_recall``.
    examples : dict planner -> Acquisition
        Trial 0 at the largest density (for figures).
    grids : dict (planner, density index, reconstruction) -> ndarray float32 (rows, cols)
        The reconstructed depth grids of trial ``keep_trial`` (:func:`run_lidar_study`), for
        an export; empty unless asked for.
    densities : list of float
        The planned densities, in the order of the grids' density index.
    ks : list of int
        The planned pixel count of each density (0: a flash without a plan).
    """

    rows: list
    examples: dict
    grids: dict = field(default_factory=dict)
    densities: list = field(default_factory=list)
    ks: list = field(default_factory=list)


class _Scores:
    """Scores of one reconstruction in the guide view (and its acquisition's yield)."""

    def __init__(
        self, truth, image, camera, metrics, hazard: HazardOptions | None, site=None, landing=None
    ):
        self.truth = np.asarray(truth, float)
        self.site = site
        self.landing = landing
        self.true_points = (
            camera.unproject_depth(self.truth) if site is not None or landing is not None else None
        )
        self.image = image
        self.camera = camera
        self.metrics = tuple(metrics)
        self.hazard = hazard
        self.true_hazards = None
        if hazard is not None:
            self.true_hazards = hazard_map(camera.unproject_depth(self.truth), hazard)

    def __call__(self, recon: np.ndarray, acq: Acquisition) -> dict:
        out = score_depth(recon, self.truth, metrics=self.metrics, image=self.image)
        detail = acq.detail
        asked = np.asarray(detail.valid).size if detail is not None else len(acq.values)
        out["valid_fraction"] = float(len(acq.values) / max(asked, 1))
        if self.hazard is not None:
            found = hazard_map(self.camera.unproject_depth(recon), self.hazard)
            out.update(detection_scores(found, self.true_hazards, np.isfinite(self.truth)))
        if self.site is not None:
            rec = self.camera.unproject_depth(np.asarray(recon, float))
            out.update(safe_site_scores(rec, self.true_points, self.site))
        if self.landing is not None:
            rec = self.camera.unproject_depth(np.asarray(recon, float))
            out.update(landing_scores(rec, self.true_points, self.landing))
        return out


@dataclass(frozen=True, eq=False)
class _Plan:
    """What the protocol repeats for one study: planners per label, densities, counts."""

    planners: dict
    dens: list
    ks: list


def _check_guide(guide) -> tuple[np.ndarray, np.ndarray]:
    image = check_image(np.asarray(guide[0], float))
    depth = np.asarray(guide[1], float)
    if image.shape[:2] != depth.shape:
        raise ValueError(f"image {image.shape[:2]} and depth {depth.shape} must have the same grid")
    return image, depth


def _study_plan(o: LidarStudyOptions, sensor, image, depth, guide: Guide) -> _Plan:
    """The study's planners (:func:`~simlunar.study.lidar_planners.lidar_planners`), or the
    one label :data:`NO_PLAN` of a sensor that needs no plan."""
    if not sensor.needs_plan:
        return _Plan({NO_PLAN: None}, [0.0], [0])
    dens = [float(d) for d in o.densities]
    ks = [sample_count(d, depth.size) for d in dens]
    return _Plan(lidar_planners(o, image, depth, ks, sensor=sensor, guide=guide), dens, ks)


def run_lidar_study(
    scene: LidarScene,
    guide: tuple[np.ndarray, np.ndarray],
    options: LidarStudyOptions | None = None,
    *,
    rng,
    sensor=None,
    reconstruction_guide: Guide | None = None,
    steps: Steps | None = None,
    keep_trial: int | None = None,
) -> LidarStudyResult:
    """Plan, acquire with a LIDAR, reconstruct and score, for every planner, density and trial.

    Parameters
    ----------
    scene : LidarScene
        Terrain, guide camera (the LIDAR's origin and boresight), BSDF, sun.
    guide : (image (rows, cols), depth (rows, cols))
        The guide camera's image and true z-depth (m; NaN where the view misses the terrain).
        Only the scores and the oracles' planner step read the depth; the sensor never does.
    options : LidarStudyOptions, optional
    rng : seed of the study; split per (planner label, trial, density) and purpose
        (planner, photon noise) with ``SeedSequence``, so adding a planner changes no other's
        numbers.
    sensor : Sensor, optional
        Measures instead of ``options.sensor`` built on ``scene`` (tests, shared captures).
    reconstruction_guide : Guide, optional
        What the guided reconstructions read; default ``Guide(image)`` (the guide camera's
        frame, light unknown: the camera is not a nadir view in general).
    steps : Steps, optional
        Where each planner's finished acquisitions are kept (:mod:`simlunar.study.steps`): a
        planner found there is not measured again; the result is the same bit for bit.
    keep_trial : int, optional
        Keep the reconstructed grids of this trial (:attr:`LidarStudyResult.grids`, for an
        export); no score changes.

    Returns
    -------
    LidarStudyResult
    """
    o = options or LidarStudyOptions()
    image, depth = _check_guide(guide)
    if sensor is None:
        cls, opts_cls = SENSORS[o.sensor]
        sensor = cls(scene, o.sensor_options or opts_cls())
    rguide = reconstruction_guide if reconstruction_guide is not None else Guide(image)
    p = _study_plan(o, sensor, image, depth, rguide)
    base = int(np.random.default_rng(rng).integers(0, 2**63))
    trials = Trials(p.planners, p.ks, int(o.trials), functools.partial(_seeds, base))
    evaluate = _Scores(depth, image, scene.camera, o.metrics, o.hazard, o.safe_site, o.landing)
    recons = reconstruction_options(o.reconstructions, outside=o.outside)
    run = functools.partial(
        run_protocol, sensor, evaluate=evaluate, outside=o.outside, reconstructions=recons,
        guide=rguide, keep_trial=keep_trial,
    )  # fmt: skip
    rows, examples, grids = _run_planners(run, trials, p.dens, steps, keep_trial)
    return LidarStudyResult(rows=rows, examples=examples, grids=grids, densities=p.dens,
                            ks=list(p.ks))  # fmt: skip


def _run_planners(run, trials: Trials, dens, steps, keep_trial) -> tuple[list, dict, dict]:
    """Every planner's step through the protocol wrapper (kept planners loaded): rows,
    examples (trial 0 at the largest density, kept whole) and the kept grids."""
    names = {label: f"lidar planner {label}" + ("" if keep_trial is None else " grids")
             for label in trials.planners}  # fmt: skip
    measures = {lb: bool(getattr(p, "measures", False)) for lb, p in trials.planners.items()}
    top = int(np.argmax(dens))

    def rows(oc) -> list[dict]:
        return _rows(oc, dens[oc.budget_index], measures[oc.label])

    def keep(oc):
        return oc if (oc.trial, oc.budget_index) == (0, top) else light_outcome(oc)

    rows_out, examples, grids = [], {}, {}
    per_planner = len(trials.ks) * int(trials.trials)
    with stage("lidar study", total=len(trials.planners) * per_planner,
               unit="acquisitions") as bar:  # fmt: skip
        for step in ProtocolSteps(steps, names).run(
            trials, run, rows=rows, keep=keep, advance=bar.advance
        ):
            rows_out += step.rows
            for oc in step.outcomes:
                for r, grid in (oc.grids or {}).items():
                    grids[(oc.label, oc.budget_index, r)] = grid
                if (oc.trial, oc.budget_index) == (0, top):
                    examples[oc.label] = oc.acquisition
            if step.loaded:
                bar.advance(per_planner)
    return rows_out, examples, grids


def beam_table(acq: Acquisition) -> np.ndarray:
    """Every sample of a LIDAR acquisition in the order the sensor took them.

    Parameters
    ----------
    acq : Acquisition
        Of a LIDAR sensor: its ``detail`` is the :class:`~simlunar.lidar.returns.LidarScan`
        (``valid``, visiting ``order``, ``times``); ``planned`` the aimed-at guide pixels
        (None for a flash without a plan: its receiver pixels, where each measured point
        projects).

    Returns
    -------
    ndarray float64, shape (n, 4)
        Per sample, in visiting order (``scan.order``, then by time where every sample has
        one: a flash's frames one after the other, a frame's dots in the plan's order):
        guide ``row``, ``col`` (index coordinates; NaN for a flash pixel that measured
        nothing), ``time`` (s from the acquisition's start; NaN where the sensor keeps none) and
        the measured z-depth (m; NaN where no return was detected).
    """
    scan = acq.detail
    valid = np.asarray(scan.valid).ravel()
    n = valid.size
    if int(valid.sum()) != len(acq.values):
        raise ValueError(
            f"the acquisition has {len(acq.values)} values for {int(valid.sum())} valid samples"
        )
    rc = np.full((n, 2), np.nan)
    if acq.planned is not None and len(acq.planned) == n:
        rc[:] = np.asarray(acq.planned, float)
    else:
        rc[valid] = np.asarray(acq.rc, float)
    depth = np.full(n, np.nan)
    depth[valid] = np.asarray(acq.values, float)
    times = np.full(n, np.nan) if scan.times is None else np.asarray(scan.times, float).ravel()
    order = np.asarray(scan.order).ravel()
    if sorted(order.tolist()) != list(range(n)):
        order = np.arange(n)  # a merged flash: its samples are already frame after frame
    table = np.c_[rc, times, depth][order]
    if np.isfinite(table[:, 2]).all():
        # by time, ties in that order: a flash's frames one after the other (the dots of one
        # frame fire together and keep the plan's order)
        table = table[np.argsort(table[:, 2], kind="stable")]
    return table


def _rows(oc, density: float, measures: bool = False) -> list[dict]:
    """Tidy rows of one outcome; a multi-round planner's carry its ``rounds`` (its
    ``seconds`` and ``frames`` are every round's)."""
    acq = oc.acquisition
    rounds = {"rounds": int(oc.rounds)} if measures else {}
    cost = {"seconds": float(acq.seconds), "energy_j": float(acq.energy_j),
            "frames": int(acq.frames), "samples": len(acq.values), **rounds}  # fmt: skip
    middle = {"density": density, "k": oc.k}
    return outcome_rows(oc, {"planner": oc.label}, middle, cost, value=float)


def _rows_of(rows: list[dict], metric: str, reconstruction: str):
    """The rows of ``metric`` and ``reconstruction`` (a row without one: the default)."""
    for r in rows:
        if r["metric"] == metric and (
            (r.get("reconstruction") or DEFAULT_RECONSTRUCTION) == reconstruction
        ):
            yield r


def time_table(
    rows: list[dict], metric: str = "mse", reconstruction: str = DEFAULT_RECONSTRUCTION
) -> dict[str, dict[str, np.ndarray]]:
    """Per planner, arrays over densities (ascending k): ``k``, mean ``seconds`` and mean
    ``value`` of ``metric`` over trials (and any other grouping the rows carry, pooled), of
    ``reconstruction``'s rows."""
    acc: dict = {}
    for r in _rows_of(rows, metric, reconstruction):
        acc.setdefault(str(r["planner"]), {}).setdefault(int(r["k"]), []).append(
            (float(r["seconds"]), float(r["value"]))
        )
    out = {}
    for label, by_k in acc.items():
        ks = sorted(by_k)
        out[label] = {
            "k": np.array(ks),
            "seconds": np.array([np.mean([s for s, _ in by_k[k]]) for k in ks]),
            "value": np.array([np.mean([v for _, v in by_k[k]]) for k in ks]),
        }
    return out


def equal_time_errors(
    rows: list[dict], times, *, metric: str = "mse", reconstruction: str = DEFAULT_RECONSTRUCTION
) -> dict[str, np.ndarray]:
    """Each planner's error at equal scan time, per unit (terrain seed), of
    ``reconstruction``'s rows.

    Per (unit, planner) the mean ``seconds`` and mean ``metric`` over trials at every k are
    interpolated linearly in log-log at ``times`` (s); NaN outside the scanned range.

    Returns
    -------
    dict planner -> float64 (units, len(times)), units in ascending order of ``unit``.
    """
    acc: dict = {}
    for r in _rows_of(rows, metric, reconstruction):
        key = (str(r["planner"]), int(float(r.get("unit", 0) or 0)))
        acc.setdefault(key, {}).setdefault(int(float(r["k"])), []).append(
            (float(r["seconds"]), float(r["value"]))
        )
    t = np.log(np.asarray(times, float))
    units = sorted({u for _, u in acc})
    out = {}
    for planner in dict.fromkeys(p for p, _ in acc):
        grid = np.full((len(units), len(t)), np.nan)
        for i, u in enumerate(units):
            by_k = acc.get((planner, u), {})
            pts = sorted(
                (np.mean([s for s, _ in v]), np.mean([e for _, e in v])) for v in by_k.values()
            )
            if len(pts) < 2:
                continue
            x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
            inside = (t >= x[0]) & (t <= x[-1])
            grid[i, inside] = np.exp(np.interp(t[inside], x, y))
        out[planner] = grid
    return out
