"""Scanner study: capture through Mitsuba, decode, scan modes, evaluation against ground truth.

``RenderCapture`` renders projector patterns seen by the rig's triangulation camera in one
:class:`~simlunar.render.scene.TerrainScene` (patterns swapped without reload), with path depth
``max_depth`` (Mitsuba convention: 2 = direct light only, >= 3 adds interreflections), optional
sun/ambient light, projector response (gamma) and blur, camera thin-lens defocus (from the
rig's :class:`~simlunar.geometry.Camera`) and per-frame sensor noise
(:func:`simlunar.imaging.sensor.apply_sensor`). ``run_scanner_study`` wires it to the scan
modes of :mod:`simlunar.scanner.modes` and scores the depth in the guide view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Rig
from simlunar.render.capture import (
    EXPOSURE_PERCENTILE,
    GuideView,
    RenderCapture,
    camera_truth,
    render_guide,
)
from simlunar.scanner import gray_code as gc
from simlunar.scanner import modes as scan_modes
from simlunar.scanner.triangulate import true_correspondences

__all__ = [
    "EXPOSURE_PERCENTILE",
    "GuideView",
    "RenderCapture",
    "ScannerStudyResult",
    "aim_rig_at_terrain",
    "bit_error_table",
    "camera_truth",
    "depth_range_from_terrain",
    "interreflection_comparison",
    "render_guide",
    "run_scanner_study",
    "scanner_ambiguity_experiment",
    "score_depth",
    "summarize",
    "true_correspondences",
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


def _gradient_weights_with_holes(truth: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """GRAD weights |grad truth| with the holes of ``truth`` (``~valid``) left out.

    As ``numpy.gradient``: central differences, one-sided at the border and, here, next to a
    hole; 0 in the holes and where a cell has no valid neighbour along an axis.
    """
    t = np.where(valid, truth, 0.0)
    grads = []
    for axis in (0, 1):
        d = np.diff(t, axis=axis)
        ok = np.diff(valid.astype(np.int8), axis=axis) == 0
        ok &= np.delete(valid, 0, axis=axis)  # both ends of each difference valid
        d = np.where(ok, d, 0.0)
        pad = [(0, 0), (0, 0)]
        pad[axis] = (1, 0)
        minus, ok_m = np.pad(d, pad), np.pad(ok, pad)  # difference to the previous cell
        pad[axis] = (0, 1)
        plus, ok_p = np.pad(d, pad), np.pad(ok, pad)  # difference to the next cell
        n = ok_m.astype(float) + ok_p
        grads.append(np.where(n > 0, (minus + plus) / np.maximum(n, 1), 0.0))
    return np.where(valid, np.hypot(*grads), 0.0)


def score_depth(
    depth: np.ndarray, truth: np.ndarray, *, metrics, image=None, mask=None
) -> dict[str, float]:
    """Sampling-study metrics of a reconstructed guide-view depth against ground truth.

    Parameters
    ----------
    depth, truth : (H, W) float64 z-depth (m); NaN in ``truth`` is excluded (also from the
        ``grad`` weights, which use differences between finite truth cells only)
    metrics : names from :data:`simlunar.metrics.METRICS` (``sal`` uses the saliency map of
        ``image`` as weights)
    image : (H, W) guide image (needed for ``sal``)
    mask : (H, W) bool, optional extra evaluation mask
    """
    from simlunar.metrics import metric

    valid = np.isfinite(truth)
    if mask is not None:
        valid &= np.asarray(mask, bool)
    t = np.where(valid, truth, 0.0)
    out = {}
    for name in metrics:
        weights = None
        if name == "grad":
            # |grad truth| from differences between valid cells only: the 0 put into the
            # holes must not make the cells next to them the steepest of the image
            weights = _gradient_weights_with_holes(truth, np.isfinite(truth))
        if name == "sal":
            if image is None:
                raise ValueError("metric 'sal' needs the guide image for its saliency weights")
            from simlunar.features import feature_map

            weights = feature_map("saliency", image)
        out[name] = float(metric(name, depth, t, weights=weights, mask=valid))
    return out


@dataclass(frozen=True, eq=False)
class ScannerStudyResult:
    """Tidy rows plus the scans behind them.

    Attributes
    ----------
    rows : list of dict
        Keys: mode, planner, budget, trial, metric, value, renders. Metrics: the requested
        sampling-study metrics, ``valid_fraction`` (guide pixels measured directly, before
        hole filling) and, for ``gray_code``, ``ber_c<i>`` / ``ber_r<i>`` (bit error rate of
        column / row bit i, MSB first, over camera pixels lit by the projector).
    guide : GuideView
    gray : GrayScan or None
    scans : dict (mode, planner, trial) -> ScanResult
    """

    rows: list
    guide: GuideView
    gray: scan_modes.GrayScan | None
    scans: dict


def bit_error_table(
    gray: scan_modes.GrayScan, truth: dict, mask=None, *, edge_margin: int = 1
) -> dict[str, float]:
    """Per-bit error rates of a gray-code decode against camera ground truth.

    ``mask`` (camera (rows, cols) bool) restricts the pixels; always only pixels lit by the
    projector in both the ground truth and the decode count, and for each bit only pixels
    ``edge_margin`` pixels away from that bit's true stripe edges
    (:func:`simlunar.scanner.gray_code.stable_bits`; 0 keeps every pixel).
    """
    dec = gray.decode
    base = truth["lit"] & dec.lit & (truth["col"] >= 0)
    m = base if mask is None else base & np.asarray(mask, bool)
    err = gc.bit_errors(dec, truth["col"], truth["row"], mask=m)
    per_bit = np.broadcast_to(m, err.shape)
    if edge_margin > 0:
        per_bit = per_bit & gc.stable_bits(
            truth["col"], truth["row"], dec.n_col_bits, dec.n_row_bits, margin=edge_margin
        )
    rates = gc.bit_error_rates(err, per_bit)
    names = [f"ber_c{i}" for i in range(dec.n_col_bits)] + [
        f"ber_r{i}" for i in range(dec.n_row_bits)
    ]
    return dict(zip(names, (float(r) for r in rates)))


def run_scanner_study(
    terrain,
    rig: Rig,
    *,
    modes=("gray_code", "ambiguity_enhancement"),
    planners=("wavelet", "random"),
    budget: float = 0.1,
    trials: int = 1,
    metrics=("mse", "grad", "sal"),
    rng=None,
    max_depth: int = 3,
    spp: int = 16,
    seed: int = 0,
    sensor=None,
    bsdf=None,
    guide_light: str = "projector",
    sun=None,
    extra_lights=(),
    projector_gamma: float = 1.0,
    projector_blur: float = 0.0,
    camera_blur: float = 0.0,
    gray_opts: dict | None = None,
    dot_opts: dict | None = None,
    planner_opts: dict | None = None,
    capture_opts: dict | None = None,
    progress=None,
) -> ScannerStudyResult:
    """Scan a terrain with a rig in several modes and score the guide-view depth.

    Parameters
    ----------
    terrain : Terrain
    rig : Rig (e.g. :func:`simlunar.scanner.rigs.moonyard_rig` aimed at the terrain)
    modes : names from :data:`simlunar.scanner.modes.MODES`
    planners : planner strategy names (:func:`simlunar.planner.plan`) for the dot modes, or
        ``"low_contrast"`` (:func:`simlunar.scanner.modes.low_contrast_pixels`: the pixels
        the gray-code scan saw least lit; ambiguity_enhancement only)
    budget : fraction of guide pixels rescanned / sampled by dots (paper: 0.1)
    trials : planner draws per (mode, planner); the gray-code scan is shared
    metrics : sampling-study metric names
    rng : seed for the sensor noise and the planners (split with ``SeedSequence.spawn``)
    max_depth, spp, seed : rendering (Mitsuba path depth convention; sampler seed)
    sensor : SensorModel or None
    bsdf : BSDF spec or None
    guide_light : "projector" (all-white frame, camera-centred) or "sun" (then ``sun``)
    extra_lights : lights on during the scan (sun, ambient)
    projector_gamma, projector_blur : projector response and defocus (sigma, projector px)
    camera_blur : camera lens point-spread function (Gaussian sigma, camera px)
    gray_opts, dot_opts : options for the gray-code scan and the dot scans
    planner_opts : dict, optional
        Planner options (:func:`simlunar.planner.plan`) by planner name, e.g.
        ``{"wavelet": {"feature_opts": {"levels": 1}}}``; planners not named get none (the
        ``random`` planner takes no options).
    capture_opts : dict, optional
        Further :class:`RenderCapture` options, e.g. ``{"sparse_integrator": "ptracer",
        "sparse_spp": 1}`` (light tracing for dot frames).
    progress : callable(str) or None

    Returns
    -------
    ScannerStudyResult
    """
    unknown = [m for m in modes if m not in scan_modes.MODES]
    if unknown:
        raise ValueError(f"unknown scan mode(s) {unknown}; valid: {sorted(scan_modes.MODES)}")
    planner_opts = dict(planner_opts or {})
    stray = sorted(set(planner_opts) - set(planners))
    if stray or not all(isinstance(v, dict) for v in planner_opts.values()):
        raise ValueError(
            f"planner_opts must map planner names {list(planners)} to option dicts, got keys "
            f"{sorted(planner_opts)}"
        )
    if int(trials) < 1:
        raise ValueError(f"trials must be >= 1, got {trials}")
    say = progress or (lambda _msg: None)
    noise_rng, plan_rng = np.random.default_rng(rng).spawn(2)
    capture = RenderCapture(
        terrain,
        rig,
        bsdf=bsdf,
        max_depth=max_depth,
        spp=spp,
        seed=seed,
        sensor=sensor,
        rng=noise_rng,
        extra_lights=extra_lights,
        projector_gamma=projector_gamma,
        projector_blur=projector_blur,
        camera_blur=camera_blur,
        **(capture_opts or {}),
    )
    guide = render_guide(
        terrain, rig, light=guide_light, sun=sun, bsdf=bsdf, max_depth=max_depth, spp=spp, seed=seed
    )
    truth_depth = np.where(guide.valid, guide.depth, np.nan)
    depth_range = depth_range_from_terrain(terrain, rig)
    rows: list[dict] = []
    scans: dict = {}

    def record(mode, planner, trial, res, extra=None):
        vals = score_depth(res.depth, truth_depth, metrics=metrics, image=guide.image)
        measured = np.isfinite(res.measured) & guide.valid
        vals["valid_fraction"] = float(measured.sum() / max(guide.valid.sum(), 1))
        vals.update(extra or {})
        for name, v in vals.items():
            rows.append(
                {
                    "mode": mode,
                    "planner": planner,
                    "budget": budget if planner else 0.0,
                    "trial": trial,
                    "metric": name,
                    "value": v,
                    "renders": res.renders,
                }
            )
        scans[(mode, planner, trial)] = res

    gray = None
    if "gray_code" in modes or "ambiguity_enhancement" in modes:
        say("gray-code scan")
        gray = scan_modes.gray_code_scan(capture, rig, **(gray_opts or {}))
        if "gray_code" in modes:
            res = scan_modes.ScanResult(
                "gray_code", scan_modes.fill_holes(gray.depth), gray.depth, gray.renders, gray=gray
            )
            extra = bit_error_table(gray, camera_truth(capture, guide))
            if capture.ambient is not None:  # a daylight scan: how bright the sun was
                extra["ambient_ratio"] = capture.ambient_ratio
            record("gray_code", "", 0, res, extra)
    plan_rngs = iter(plan_rng.spawn(len(planners) * int(trials) * len(modes)))
    for mode in modes:
        if mode == "gray_code":
            continue
        for planner in planners:
            for trial in range(int(trials)):
                say(f"{mode} / {planner} / trial {trial}")
                kw = {
                    "guide_image": guide.image,
                    "planner": planner,
                    "rng": next(plan_rngs),
                    "depth_range": depth_range,
                    "budget": budget,
                    "dot_opts": dot_opts,
                    "planner_opts": planner_opts.get(planner),
                }
                if mode == "ambiguity_enhancement":
                    kw["gray"] = gray
                res = scan_modes.scan(mode, capture, rig, **kw)
                record(mode, planner, trial, res)
    return ScannerStudyResult(rows=rows, guide=guide, gray=gray, scans=scans)


def interreflection_comparison(
    terrain,
    rig: Rig,
    *,
    depths=(2, 3),
    mask_fn=None,
    spp: int = 16,
    seed: int = 0,
    bsdf=None,
    gray_opts: dict | None = None,
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
        cap = RenderCapture(terrain, rig, bsdf=bsdf, max_depth=depth, spp=spp, seed=seed)
        g = scan_modes.gray_code_scan(cap, rig, **(gray_opts or {}))
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
    from simlunar.scanner.rigs import RIG_PRESETS, rig_preset

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


def scanner_ambiguity_experiment(
    *,
    terrain: str = "moonyard",
    terrain_scale: float = 0.35,
    seed: int = 0,
    rig_preset: str = "moonyard",
    proj_size=(128, 96),
    cam_size=(256, 192),
    budget: float = 0.1,
    planners=("wavelet", "random"),
    trials: int = 3,
    spp: int = 32,
    max_depth: int = 3,
    sensor: bool = True,
    projector_blur: float = 0.0,
    camera_blur: float = 1.0,
    subpixel: bool = True,
    cam_fov_x_deg: float | None = 60.0,
    wavelet_levels: int | None = 1,
    metrics=("mse", "grad", "sal"),
    progress=None,
) -> list[dict]:
    """The paper's ambiguity-enhancement experiment (section 5) with plain arguments.

    Generates the terrain preset (``terrain_scale`` shrinks the grid), aims the rig preset at
    it, scans with full gray code and then rescans ``budget`` of the guide pixels with dots
    chosen by each planner, and returns tidy rows (see :func:`run_scanner_study`). With
    ``sensor`` a 12-bit sensor with shot and read noise captures every frame.

    The defaults are the conditions of ``experiments/scanner_ambiguity.yaml``: a camera lens
    PSF of ``camera_blur`` px (sigma), sub-pixel stripe-edge refinement (``subpixel``), a
    triangulation camera field of view of ``cam_fov_x_deg`` (None: the projector's) so it sees
    the whole projection, and the wavelet planner's map restricted to the finest
    ``wavelet_levels`` levels (None: all levels).
    """
    from simlunar.terrain import generate

    t_rng, s_rng = np.random.default_rng(seed).spawn(2)
    terr = generate(terrain, rng=t_rng, scale=terrain_scale).terrain
    rig_kw = {} if cam_fov_x_deg is None else {"cam_fov_x": np.radians(cam_fov_x_deg)}
    rig = aim_rig_at_terrain(
        terr, preset=rig_preset, proj_size=proj_size, cam_size=cam_size, **rig_kw
    )
    planner_opts = {}
    if wavelet_levels is not None and "wavelet" in planners:
        planner_opts["wavelet"] = {"feature_opts": {"levels": int(wavelet_levels)}}
    sens = None
    if sensor:
        from simlunar.imaging.sensor import SensorModel

        sens = SensorModel(full_well_e=20000.0, read_noise_e=5.0, bits=12)
    res = run_scanner_study(
        terr,
        rig,
        modes=("gray_code", "ambiguity_enhancement"),
        planners=planners,
        budget=budget,
        trials=trials,
        metrics=metrics,
        rng=s_rng,
        max_depth=max_depth,
        spp=spp,
        seed=seed,
        sensor=sens,
        projector_blur=projector_blur,
        camera_blur=camera_blur,
        gray_opts={"subpixel": bool(subpixel)},
        planner_opts=planner_opts,
        progress=progress,
    )
    return res.rows


def summarize(rows: list[dict], metric: str = "mse") -> dict[str, float]:
    """Mean ``metric`` per (mode, planner) as ``{"gray_code": v, "ambiguity_enhancement/wavelet": v}``."""
    acc: dict[str, list[float]] = {}
    for r in rows:
        if r["metric"] != metric:
            continue
        key = r["mode"] if not r["planner"] else f"{r['mode']}/{r['planner']}"
        acc.setdefault(key, []).append(r["value"])
    return {k: float(np.mean(v)) for k, v in acc.items()}
