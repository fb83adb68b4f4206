"""The scanner study (paper section 5): the study protocol with the structured-light sensor.

A projector-camera rig (:class:`~simlunar.geometry.Rig`) scans a terrain through a
:class:`~simlunar.render.capture.RenderCapture` in each scan mode of
:class:`~simlunar.sensors.structured_light.StructuredLight` (a full scan with any full-field
coding of :data:`~simlunar.scanner.codings.CODINGS`; ambiguity enhancement and data reduction
rescan the pixels a planner chose with dots); the protocol
(:mod:`simlunar.study.protocol`) reconstructs every scan in the guide view and scores it
against the guide view's ground truth.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from simlunar.features import check_image
from simlunar.geometry import Rig
from simlunar.planner import DEFAULT_PLANNER, plan, strategy_weights
from simlunar.reconstruction import Guide
from simlunar.render.capture import (
    CaptureOptions,
    GuideView,
    RenderCapture,
    camera_truth,
    render_guide,
)
from simlunar.scanner import gray_errors
from simlunar.scanner.codings import DEFAULT_CODING, coding_for
from simlunar.scanner.rigs import RIG_PRESETS, rig_preset
from simlunar.scanner.scans import (
    SCAN_PLANNERS,
    CodedScan,
    DotOptions,
    GrayCodeOptions,
    GrayScan,
    gray_code_scan,
    low_contrast_pixels,
)
from simlunar.sensors.structured_light import (
    DOT_MODES,
    MODES,
    StructuredLight,
    StructuredLightOptions,
    mode_coding,
)
from simlunar.study.depth_scores import score_depth
from simlunar.study.protocol import (
    DEFAULT_RECONSTRUCTION,
    Trials,
    reconstruction_options,
    run_protocol,
)
from simlunar.study.sampling import _cost

__all__ = [
    "ScannerScene",
    "ScannerStudyOptions",
    "ScannerStudyResult",
    "aim_rig_at_terrain",
    "bit_error_table",
    "depth_range_from_terrain",
    "guided_weights",
    "interreflection_comparison",
    "run_scanner_study",
    "summarize",
]


def depth_range_from_terrain(terrain, rig: Rig, *, margin: float = 0.05) -> tuple[float, float]:
    """Projector z-depth range of the terrain's cell centres inside the projector's view (m)."""
    pts = terrain.points().reshape(-1, 3)
    pts = pts[np.isfinite(pts).all(axis=1)]
    uv, z = rig.projector.project(pts)
    H, W = rig.projector.intrinsics.shape
    inside = (z > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < W) & (uv[:, 1] >= 0) & (uv[:, 1] < H)
    if not inside.any():
        raise ValueError("the projector does not see the terrain")
    z = z[inside]
    return (float(z.min() * (1 - margin)), float(z.max() * (1 + margin)))


def bit_error_table(
    gray: GrayScan, truth: dict, mask=None, *, edge_margin: int = 1
) -> dict[str, float]:
    """Per-bit error rates of a gray-code decode against camera ground truth.

    ``mask`` (camera (rows, cols) bool) restricts the pixels; always only pixels lit by the
    projector in both the ground truth and the decode count, and for each bit only pixels
    ``edge_margin`` pixels away from that bit's true stripe edges
    (:func:`simlunar.scanner.gray_errors.stable_bits`; 0 keeps every pixel).
    """
    return gray_errors.bit_error_table(gray.decode, truth, mask, edge_margin=edge_margin)


@dataclass(frozen=True, eq=False)
class ScannerScene:
    """What a scanner study scans: the terrain, the rig and the light.

    Attributes
    ----------
    terrain : Terrain
    rig : Rig (e.g. :func:`aim_rig_at_terrain`)
    bsdf : BSDF spec or None (Lambert)
    camera_model : SensorModel or None
        The triangulation camera's sensor (noise, quantisation); None: noise-free frames.
    sun : SunLight or None
        The sun of a sun-lit guide image (``guide_light="sun"``).
    extra_lights : tuple of light specs
        Lights on during the scan (a daylight scan: the sun and sky).
    """

    terrain: object
    rig: Rig
    bsdf: object = None
    camera_model: object = None
    sun: object = None
    extra_lights: tuple = ()


@dataclass(frozen=True)
class ScannerStudyOptions:
    """What a scanner study runs.

    Attributes
    ----------
    modes : names from :data:`simlunar.sensors.structured_light.MODES`
    planners : planner strategy names (:func:`simlunar.planner.plan`) for the dot modes, or
        ``"low_contrast"`` (:func:`simlunar.scanner.scans.low_contrast_pixels`: the pixels the
        coded scan saw least lit; ambiguity_enhancement only)
    budget : fraction of guide pixels rescanned / sampled by dots (paper: 0.1)
    trials : planner draws per (mode, planner); the gray-code scan is shared
    metrics : sampling-study metric names
    guide_light : "projector" (all-white frame, camera-centred) or "sun"
    capture : CaptureOptions (path depth, samples, projector and lens optics)
    coding : the full-field coding ambiguity enhancement rescans
        (:data:`simlunar.scanner.codings.CODINGS`)
    codings : mapping coding name -> its options object (codings not named: defaults)
    dots : DotOptions
    keep_frames : keep the coded scans' captured stacks (the scan export needs them)
    planner_opts : mapping planner name -> planner options (:func:`simlunar.planner.plan`),
        e.g. ``{"wavelet": {"feature_opts": {"levels": 1}}}``; planners not named get none
    reconstructions : mapping name -> options, or names
        Reconstructions of :data:`simlunar.reconstruction.RECONSTRUCTIONS` run on every scan
        (default ``linear`` alone); a guided one reads the guide camera's image.
    """

    modes: tuple = (DEFAULT_CODING, "ambiguity_enhancement")
    planners: tuple = (DEFAULT_PLANNER, "random")
    budget: float = 0.1
    trials: int = 1
    metrics: tuple = ("mse", "grad", "sal")
    guide_light: str = "projector"
    capture: CaptureOptions = field(default_factory=CaptureOptions)
    coding: str = DEFAULT_CODING
    codings: Mapping = field(default_factory=dict)
    dots: DotOptions = field(default_factory=DotOptions)
    planner_opts: Mapping = field(default_factory=dict)
    reconstructions: Mapping | tuple = (DEFAULT_RECONSTRUCTION,)
    keep_frames: bool = False

    def __post_init__(self):
        reconstruction_options(self.reconstructions)
        unknown = [m for m in self.modes if m not in MODES]
        if unknown:
            raise ValueError(f"unknown scan mode(s) {unknown}; valid: {sorted(MODES)}")
        stray = sorted(set(self.planner_opts) - set(self.planners))
        if stray or not all(isinstance(v, Mapping) for v in self.planner_opts.values()):
            raise ValueError(
                f"planner_opts must map planner names {list(self.planners)} to option dicts, "
                f"got keys {sorted(self.planner_opts)}"
            )
        if int(self.trials) < 1:
            raise ValueError(f"trials must be >= 1, got {self.trials}")
        if not 0 < self.budget <= 1:
            raise ValueError(f"budget must be a fraction in (0, 1], got {self.budget}")
        # the coding and its options are checked as the sensor checks them
        StructuredLightOptions(coding=self.coding, codings=self.codings)

    def sensor_options(self, mode: str) -> StructuredLightOptions:
        """The structured-light sensor's options for scan ``mode``."""
        return StructuredLightOptions(
            mode, self.coding, self.codings, self.dots, keep_frames=self.keep_frames
        )

    def scanned_codings(self) -> list[str]:
        """The full-field codings the modes project, in the order they are scanned."""
        names = (mode_coding(m, self.coding) for m in self.modes)
        return list(dict.fromkeys(n for n in names if n is not None))


@dataclass(frozen=True, eq=False)
class ScannerStudyResult:
    """Tidy rows plus the scans behind them.

    Attributes
    ----------
    rows : list of dict
        Keys: mode, planner, reconstruction, budget, trial, metric, value, renders (and, for a
        reconstruction that read guide frames, guide_frames and exposures). Metrics: the requested
        sampling-study metrics, ``valid_fraction`` (guide pixels measured directly, before
        hole filling) and, for a full-field coding's mode, its decode errors against the
        truth (the coding's ``truth_scores``: the gray code's ``ber_c<i>`` / ``ber_r<i>``, bit
        error rate of column / row bit i, MSB first, over camera pixels lit by the projector).
    guide : GuideView
    coded : dict coding name -> CodedScan
        The full-field scans, in the order they were made (shared by the modes).
    scans : dict (mode, planner, trial) -> ScanResult
    """

    rows: list
    guide: GuideView
    coded: dict
    scans: dict

    @property
    def exported(self) -> CodedScan | None:
        """The scan the scan export writes: the first full-field scan made (None if none)."""
        return next(iter(self.coded.values()), None)


def run_scanner_study(
    scene: ScannerScene,
    options: ScannerStudyOptions | None = None,
    *,
    rng=None,
    progress=None,
    reconstruction_guide: Guide | None = None,
) -> ScannerStudyResult:
    """Scan a terrain with a rig in several modes and score the guide-view depth.

    Parameters
    ----------
    scene : ScannerScene
    options : ScannerStudyOptions, optional
    rng : seed for the sensor noise and the planners (split with ``SeedSequence.spawn``)
    progress : callable(str) or None
    reconstruction_guide : Guide, optional
        What the guided reconstructions read; default the guide view's image (one frame named
        after ``guide_light``, light unknown: the rig camera is not a nadir view).

    Returns
    -------
    ScannerStudyResult
    """
    o = options or ScannerStudyOptions()
    say = progress or (lambda _msg: None)
    noise_rng, plan_rng = np.random.default_rng(rng).spawn(2)
    capture, guide = _capture_and_guide(scene, o, noise_rng)
    depth_range = depth_range_from_terrain(scene.terrain, scene.rig)
    coded: dict[str, CodedScan] = {}
    for name in o.scanned_codings():  # every full-field scan once, before the dots
        say(f"{name} scan")
        coding = coding_for(o.codings, name)
        coded[name] = coding.scan(capture, scene.rig, keep_frames=o.keep_frames)
    evaluate = _ScanScores(guide, o.metrics, capture)
    recons = reconstruction_options(o.reconstructions)
    rguide = reconstruction_guide
    if rguide is None:
        rguide = Guide(np.asarray(guide.image, float), frames=(o.guide_light,))
    seeds = _plan_seeds(o, plan_rng)
    rows: list[dict] = []
    scans: dict = {}
    for mode in sorted(o.modes, key=lambda m: m in DOT_MODES):  # full-field scans first
        options = o.sensor_options(mode)
        name = options.scanned_coding
        sensor = StructuredLight(
            capture,
            scene.rig,
            depth_range=depth_range,
            options=options,
            coded=None if name is None else coded[name],
        )
        trials = _mode_trials(o, mode, sensor, guide, seeds)
        for outcomes in run_protocol(
            sensor, trials, evaluate, reconstructions=recons, guide=rguide
        ):
            for oc in outcomes:
                planner = oc.label if sensor.needs_plan else ""
                say(f"{mode} / {planner} / trial {oc.trial}" if planner else "")
                rows += _rows(mode, planner, oc, o.budget)
                scans[(mode, planner, oc.trial)] = oc.acquisition.detail
    return ScannerStudyResult(rows=rows, guide=guide, coded=coded, scans=scans)


def _capture_and_guide(scene: ScannerScene, o: ScannerStudyOptions, noise_rng):
    """The scene's render capture (sensor noise from ``noise_rng``) and its guide view."""
    c = o.capture
    capture = RenderCapture(
        scene.terrain,
        scene.rig,
        c,
        bsdf=scene.bsdf,
        sensor=scene.camera_model,
        rng=noise_rng,
        extra_lights=scene.extra_lights,
    )
    guide = render_guide(
        scene.terrain,
        scene.rig,
        light=o.guide_light,
        sun=scene.sun,
        bsdf=scene.bsdf,
        max_depth=c.max_depth,
        spp=c.spp,
        seed=c.seed,
    )
    return capture, guide


def _plan_seeds(o: ScannerStudyOptions, plan_rng) -> dict:
    """(mode, planner, trial) -> planner rng, in the order the study has always drawn them."""
    it = iter(plan_rng.spawn(len(o.planners) * int(o.trials) * len(o.modes)))
    return {
        (mode, planner, t): next(it)
        for mode in o.modes
        if mode in DOT_MODES
        for planner in o.planners
        for t in range(int(o.trials))
    }


def _mode_trials(o, mode: str, sensor: StructuredLight, guide: GuideView, seeds) -> Trials:
    """The protocol's trials of one scan mode: no plan for a full-field coding."""
    if not sensor.needs_plan:
        return Trials({"": None}, [0], 1, lambda *_: (None, None))
    H, W = sensor.proj_shape
    k = max(1, round(o.budget * H * W))
    planners = {p: _scan_planner(p, o, mode, guide, sensor) for p in o.planners}
    return Trials(planners, [k], int(o.trials), lambda p, t, _b: (seeds[(mode, p, t)], None))


def guided_weights(name: str, image: np.ndarray, opts: Mapping) -> tuple[np.ndarray, dict]:
    """The weights of strategy ``name`` on the guide ``image`` (with the ``feature_opts`` and
    ``coefficients`` of its options ``opts``) and the rest of ``opts``: the keywords of its
    :func:`~simlunar.planner.plan`."""
    rest = dict(opts)
    feature_opts = rest.pop("feature_opts", None)
    coefficients = rest.pop("coefficients", None)
    return strategy_weights(name, image, feature_opts=feature_opts, coefficients=coefficients), rest


def _scan_planner(name: str, o, mode: str, guide: GuideView, sensor: StructuredLight):
    """The planner of the guide pixels to rescan: from the guide image, or from the coded
    scan for a :data:`~simlunar.scanner.scans.SCAN_PLANNERS` planner."""
    opts = o.planner_opts.get(name, {})
    if name in SCAN_PLANNERS:
        if mode != "ambiguity_enhancement":
            raise ValueError(
                f"planner {name!r} ranks the pixels of a coded scan: use it with the "
                "ambiguity_enhancement mode"
            )
        if opts:
            raise ValueError(f"planner {name!r} takes no options, got {sorted(opts)}")
        return lambda k, rng: low_contrast_pixels(sensor.coded_scan(), k, rng=rng)
    image = check_image(np.asarray(guide.image, float))
    weights, opts = guided_weights(name, image, opts)

    def planner(k, rng):
        p = plan(name, int(k), weights=weights, shape=image.shape, rng=rng, **opts)
        return np.stack([np.asarray(p.rows), np.asarray(p.cols)], axis=-1).astype(np.int64)

    return planner


class _ScanScores:
    """Scores of a reconstructed scan in the guide view, its valid fraction and, for a
    full-field coding's mode, the coding's decode errors against the truth (and the
    sun-to-projector ratio of a daylight scan)."""

    def __init__(self, guide: GuideView, metrics, capture: RenderCapture):
        self.guide = guide
        self.truth = np.where(guide.valid, guide.depth, np.nan)
        self.metrics = tuple(metrics)
        self.capture = capture

    def __call__(self, recon: np.ndarray, acquisition) -> dict:
        g = self.guide
        vals = score_depth(recon, self.truth, metrics=self.metrics, image=g.image)
        measured = np.isfinite(acquisition.detail.measured) & g.valid
        vals["valid_fraction"] = float(measured.sum() / max(g.valid.sum(), 1))
        detail = acquisition.detail
        if detail.mode not in DOT_MODES:  # a full-field coding's own mode
            coded = detail.coded
            vals.update(coded.coding.truth_scores(coded, camera_truth(self.capture, g)))
            if self.capture.ambient is not None:  # a daylight scan: how bright the sun was
                vals["ambient_ratio"] = self.capture.ambient_ratio
        return vals


def _rows(mode: str, planner: str, oc, budget: float) -> list[dict]:
    return [
        {
            "mode": mode,
            "planner": planner,
            "reconstruction": r,
            **_cost(oc.recon_info[r]),
            "budget": budget if planner else 0.0,
            "trial": oc.trial,
            "metric": name,
            "value": v,
            "renders": oc.acquisition.frames,
        }
        for r, scores in oc.recon_scores.items()
        for name, v in scores.items()
    ]


def interreflection_comparison(
    terrain,
    rig: Rig,
    *,
    depths=(2, 3),
    mask_fn=None,
    spp: int = 16,
    seed: int = 0,
    bsdf=None,
    gray: GrayCodeOptions | None = None,
) -> dict:
    """Gray-code bit error rates with and without interreflections.

    Parameters
    ----------
    depths : path depths to compare (Mitsuba convention: 2 = direct only, >= 3 interreflections)
    mask_fn : callable(positions (rows, cols, 3)) -> bool (rows, cols), optional
        Selects camera pixels by the world point they see (e.g. inside craters).

    Returns
    -------
    dict depth -> dict of ``ber_c<i>`` / ``ber_r<i>`` rates (noise-free frames)
    """
    guide = render_guide(terrain, rig, spp=spp, seed=seed, bsdf=bsdf, max_depth=2)
    out = {}
    for depth in depths:
        cap = RenderCapture(
            terrain, rig, CaptureOptions(max_depth=depth, spp=spp, seed=seed), bsdf=bsdf
        )
        g = gray_code_scan(cap, rig, gray)
        truth = camera_truth(cap, guide)
        mask = None
        if mask_fn is not None:
            mask = np.asarray(mask_fn(np.asarray(cap.scene.ground_truth().position)), bool)
        out[depth] = bit_error_table(g, truth, mask)
    return out


def aim_rig_at_terrain(
    terrain,
    *,
    preset: str = "moonyard",
    proj_size=(128, 96),
    cam_size=(256, 192),
    fill: float = 0.9,
    **kw,
) -> Rig:
    """A preset rig aimed at the terrain's centre, at the standoff that fits the projection in it.

    The projector's horizontal footprint is ``fill`` times the smaller side of the terrain (so
    every guide pixel sees terrain). Extra keywords go to the preset (elevation, baseline, ...).
    """
    if preset not in RIG_PRESETS:
        raise ValueError(f"unknown rig preset {preset!r}; valid: {sorted(RIG_PRESETS)}")
    xmin, xmax, ymin, ymax = terrain.extent
    target = np.array([(xmin + xmax) / 2, (ymin + ymax) / 2, float(np.nanmedian(terrain.heights))])
    fov = kw.pop("fov_x", np.radians(50.0) if preset == "moonyard" else np.radians(30.0))
    side = min(xmax - xmin, (ymax - ymin) * proj_size[0] / proj_size[1])
    dist = fill * side / (2 * np.tan(fov / 2))
    if preset == "moonyard":
        kw.setdefault("distance", dist)
        kw.setdefault("baseline", 0.25 * dist)
    else:
        kw.setdefault("altitude", dist)
        kw.setdefault("baseline", 0.15 * dist)
    return rig_preset(
        preset, target=target, proj_size=tuple(proj_size), cam_size=tuple(cam_size), fov_x=fov, **kw
    )


def summarize(
    rows: list[dict], metric: str = "mse", reconstruction: str = DEFAULT_RECONSTRUCTION
) -> dict[str, float]:
    """Mean ``metric`` of ``reconstruction``'s rows per (mode, planner) as
    ``{"gray_code": v, "ambiguity_enhancement/wavelet": v}``."""
    acc: dict[str, list[float]] = {}
    for r in rows:
        if r["metric"] != metric:
            continue
        if r.get("reconstruction", DEFAULT_RECONSTRUCTION) != reconstruction:
            continue
        key = r["mode"] if not r["planner"] else f"{r['mode']}/{r['planner']}"
        acc.setdefault(key, []).append(r["value"])
    return {k: float(np.mean(v)) for k, v in acc.items()}
