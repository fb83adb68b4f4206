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

import dataclasses
import functools
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from simlunar.geometry import Rig
from simlunar.planner import DEFAULT_PLANNER
from simlunar.progress import stage
from simlunar.reconstruction import RECONSTRUCTIONS, Guide
from simlunar.render.capture import (
    CaptureOptions,
    GuideView,
    RenderCapture,
    camera_truth,
    render_guide,
)
from simlunar.render.lights import SunLight
from simlunar.scanner.codings import DEFAULT_CODING, coding_for
from simlunar.scanner.dot_scan import DotOptions
from simlunar.scanner.result import CodedScan
from simlunar.sensors.structured_light import (
    DOT_MODES,
    MODES,
    StructuredLight,
    StructuredLightOptions,
    mode_coding,
)
from simlunar.study._bit_errors import bit_error_table, interreflection_comparison
from simlunar.study.depth_scores import score_depth
from simlunar.study.protocol import (
    DEFAULT_RECONSTRUCTION,
    Trials,
    light_outcome,
    outcome_rows,
    reconstruction_of,
    reconstruction_options,
    run_protocol,
)
from simlunar.study.scanner_setup import (
    _scan_planner,
    aim_rig_at_terrain,
    depth_range_from_terrain,
    guided_weights,
)
from simlunar.study.steps import ProtocolSteps, Steps, resumable

__all__ = [
    "CAMERA_FRAME",
    "ScannerScene",
    "ScannerStudyOptions",
    "ScannerStudyResult",
    "aim_rig_at_terrain",
    "bit_error_table",
    "depth_range_from_terrain",
    "guided_weights",
    "interreflection_comparison",
    "run_scanner_study",
    "scanner_guide",
    "summarize",
    "sun_frame_name",
]

#: name of the projector's flood frame among the guide frames (a co-located light)
CAMERA_FRAME = "camera"


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
        ``"low_contrast"`` (:func:`simlunar.scanner.rescan.low_contrast_pixels`: the pixels the
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
    guide_frames : tuple of ``"camera"`` or SunLight specs
        Extra frames of the guide view for the guided reconstructions, rendered only when one
        is configured: ``"camera"`` is the projector's flood frame (its all-white frame: the
        paper's section 5 lights every pixel before a scan), a light co-located with the guide
        camera, so nearly pure albedo: with a sun guide (``guide_light="sun"``) it becomes the
        :attr:`Guide.flat <simlunar.reconstruction.Guide>` whose ratio cancels albedo; a
        SunLight spec renders the guide view under another sun (:attr:`Guide.others`,
        photometric stereo). The rig camera is not a nadir view: the frames' light directions
        are left unknown (the reconstruction calibrates them from the samples).
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
    guide_frames: tuple = ()

    def __post_init__(self):
        reconstruction_options(self.reconstructions)
        object.__setattr__(self, "guide_frames", tuple(self.guide_frames))
        for f in self.guide_frames:
            if f == CAMERA_FRAME:
                if self.guide_light == "projector":
                    raise ValueError(
                        "guide_frames: camera (the projector's flood frame) is the guide "
                        "view's own light already (guide_light: projector)"
                    )
            elif not isinstance(f, SunLight):
                raise ValueError(f"guide_frames: each is 'camera' or a SunLight spec, got {f!r}")
        if self.guide_frames.count(CAMERA_FRAME) > 1:
            raise ValueError("guide_frames: camera is listed twice")
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
    steps: Steps | None = None,
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
    steps : Steps, optional
        Where finished coded scans and (mode, planner) rescans are kept
        (:mod:`simlunar.study.steps`): those found there are not scanned again, and the result
        is the same bit for bit.

    Returns
    -------
    ScannerStudyResult
    """
    o = options or ScannerStudyOptions()
    say = progress or (lambda _msg: None)
    noise_rng, plan_rng = np.random.default_rng(rng).spawn(2)
    with stage("white frame and guide view", total=1) as s:
        capture, guide = _capture_and_guide(scene, o, noise_rng)
        s.advance()
    depth_range = depth_range_from_terrain(scene.terrain, scene.rig)
    modes = sorted(o.modes, key=lambda m: m in DOT_MODES)  # full-field scans first
    n_steps = len(o.scanned_codings()) + sum(
        len(o.planners) if m in DOT_MODES else 1 for m in modes
    )
    # each step is kept in ``steps`` with the capture's noise stream after it (every frame
    # draws its noise from that one stream): a resumed study draws what this one draws
    streams = (capture.rng,)
    coded: dict[str, CodedScan] = {}
    with stage("scanner study", total=n_steps, unit="steps") as bar:
        for name in o.scanned_codings():  # every full-field scan once, before the dots
            say(f"{name} scan")
            scan = functools.partial(_coded_scan, o, name, capture, scene.rig)
            coded[name], _ = resumable(steps, f"coded scan {name}", scan, streams=streams)
            bar.advance()
        evaluate = _ScanScores(guide, o.metrics, capture)
        recons = reconstruction_options(o.reconstructions)
        rguide = reconstruction_guide
        if rguide is None:
            rguide = scanner_guide(scene, o, guide, recons)
        seeds = _plan_seeds(o, plan_rng)
        rows: list[dict] = []
        scans: dict = {}
        for mode in modes:
            options = o.sensor_options(mode)
            shared = None if options.scanned_coding is None else coded[options.scanned_coding]
            sensor = StructuredLight(
                capture, scene.rig, depth_range=depth_range, options=options, coded=shared
            )
            trials = _mode_trials(o, mode, sensor, guide, seeds)
            # one step per planner (one for a full-field mode), through the protocol wrapper
            names = {lb: f"scan mode {mode}" + (f" planner {lb}" if lb else "")
                     for lb in trials.planners}  # fmt: skip
            run = functools.partial(_mode_tasks, sensor, evaluate, recons, rguide, say)
            row = functools.partial(_rows, mode, sensor.needs_plan, o.budget)
            store = ProtocolSteps(steps, names, streams=streams)
            for step in store.run(trials, run, rows=row, keep=_without_samples):
                rows += step.rows
                for oc in step.outcomes:
                    planner = oc.label if sensor.needs_plan else ""
                    # the shared coded scan is not kept with every step: put back
                    detail = dataclasses.replace(oc.acquisition.detail, coded=shared)
                    scans[(mode, planner, oc.trial)] = detail
                bar.advance()
    return ScannerStudyResult(rows=rows, guide=guide, coded=coded, scans=scans)


def _coded_scan(o: ScannerStudyOptions, name: str, capture, rig: Rig) -> CodedScan:
    """The full-field scan with coding ``name``; its frames counted as a progress stage."""
    coding = coding_for(o.codings, name)
    frames = coding.frames(rig.projector.intrinsics.shape)
    with stage(f"{name} scan", total=frames, unit="frames"):
        return coding.scan(capture, rig, keep_frames=o.keep_frames)


def _mode_tasks(sensor, evaluate, recons, rguide, say, trials: Trials):
    """The protocol's tasks of one scan mode's planners, planner by planner (each asked for
    only when the wrapper reaches it: the capture's noise stream is then where it left it)."""
    for label, planner in trials.planners.items():
        one = dataclasses.replace(trials, planners={label: planner})
        yield from _mode_step(sensor, one, evaluate, recons, rguide, say)


def _mode_step(sensor, trials: Trials, evaluate, recons, rguide, say) -> list:
    """The tasks of one (scan mode, planner): a list of outcomes per trial, in order."""
    out = []
    (label,) = trials.planners
    mode = sensor.options.mode
    with stage(f"{mode} {label}".strip(), total=int(trials.trials), unit="trials") as bar:
        for outcomes in run_protocol(
            sensor, trials, evaluate, reconstructions=recons, guide=rguide
        ):
            for oc in outcomes:
                planner = oc.label if sensor.needs_plan else ""
                say(f"{mode} / {planner} / trial {oc.trial}" if planner else "")
            out.append(outcomes)
            bar.advance()
    return out


def _without_samples(oc):
    """What a scan step keeps of an outcome: its scores and cost, and the scan detail
    without the shared coded scan (put back when the step is read)."""
    light = light_outcome(oc)
    detail = dataclasses.replace(oc.acquisition.detail, coded=None)
    return dataclasses.replace(
        light, acquisition=dataclasses.replace(light.acquisition, detail=detail)
    )


def scanner_guide(
    scene: ScannerScene, o: ScannerStudyOptions, guide: GuideView, recons: Mapping
) -> Guide:
    """What the guided reconstructions of a scanner study read: the guide view's image (named
    after ``guide_light``) and, when a configured reconstruction is guided, the frames of
    ``o.guide_frames`` rendered in the same view with the guide's render settings (frame i
    with seed ``capture.seed + 1 + i``): ``camera``, the projector's flood frame, becomes
    :attr:`Guide.flat`; each other sun one of :attr:`Guide.others` (direction unknown).
    """
    image = np.asarray(guide.image, float)
    guided = any(RECONSTRUCTIONS[reconstruction_of(v)].meta.get("guided") for v in recons.values())
    if not guided or not o.guide_frames:
        return Guide(image, frames=(o.guide_light,))
    c = o.capture
    flat, others, names = None, [], [o.guide_light]
    for i, frame in enumerate(o.guide_frames):
        camera = frame == CAMERA_FRAME
        view = render_guide(
            scene.terrain,
            scene.rig,
            light="projector" if camera else "sun",
            sun=None if camera else frame,
            bsdf=scene.bsdf,
            max_depth=c.max_depth,
            spp=c.spp,
            seed=c.seed + 1 + i,
        )
        if camera:
            flat = view.image
            names.append(CAMERA_FRAME)
        else:
            others.append((view.image, None))
            names.append(sun_frame_name(frame))
    return Guide(image, flat=flat, others=tuple(others), frames=tuple(names))


def sun_frame_name(sun: SunLight) -> str:
    """``sun_el<e>_az<a>`` (degrees) of a further sun's guide frame."""
    return f"sun_el{np.degrees(sun.elevation):g}_az{np.degrees(sun.azimuth):g}"


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


def _rows(mode: str, planned: bool, budget: float, oc) -> list[dict]:
    """Tidy rows of one outcome: mode, planner ("" for a full-field mode), reconstruction, its
    guide frames, budget, trial, metric, value, renders."""
    planner = oc.label if planned else ""
    middle = {"budget": budget if planner else 0.0}
    tail = {"renders": oc.acquisition.frames}
    return outcome_rows(oc, {"mode": mode, "planner": planner}, middle, tail)


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
