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

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from simlunar.geometry import Rig
from simlunar.scanner import gray_code as gc
from simlunar.scanner import modes as scan_modes
from simlunar.scanner.triangulate import check_rig, projector_visibility, true_correspondences

#: white-frame radiance percentile mapped to ``target_level`` by the auto exposure
EXPOSURE_PERCENTILE = 99.0


class RenderCapture:
    """Mitsuba-backed capture for :mod:`simlunar.scanner.modes`.

    Parameters
    ----------
    terrain : Terrain
    rig : Rig
    bsdf : BSDF spec or None (Lambert)
    max_depth : int
        Path depth (2 = direct only; >= 3 includes interreflections).
    spp, seed : int
        Samples per pixel and sampler seed for every pattern.
    sensor : SensorModel or None
        Per-frame noise, quantisation and response; None returns noise-free frames.
    rng : seed or Generator
        Noise stream (separate from the renderer's seed).
    extra_lights : sequence of light specs
        Sun or ambient light that stays on during the scan (appears in the black frame).
    projector_scale : float
        Projector irradiance scale (Mitsuba ``scale``).
    projector_gamma : float
        Projector response: pattern values ``p`` are emitted as ``p ** projector_gamma``.
    projector_blur : float
        Gaussian blur (sigma, projector pixels) of every emitted pattern (projector defocus).
    target_level : float
        The auto exposure maps the white frame's 99th-percentile radiance to this fraction of
        the sensor range (or of 1 without a sensor), so thresholds are in [0, 1] frame units.
    """

    def __init__(
        self,
        terrain,
        rig: Rig,
        *,
        bsdf=None,
        max_depth: int = 3,
        spp: int = 16,
        seed: int = 0,
        sensor=None,
        rng=None,
        extra_lights=(),
        projector_scale: float = 1.0,
        projector_gamma: float = 1.0,
        projector_blur: float = 0.0,
        target_level: float = 0.8,
    ) -> None:
        from simlunar.render.lights import ProjectorLight
        from simlunar.render.scene import TerrainScene

        check_rig(rig)
        if not projector_gamma > 0:
            raise ValueError(f"projector_gamma must be > 0, got {projector_gamma}")
        if projector_blur < 0:
            raise ValueError(f"projector_blur must be >= 0 px, got {projector_blur}")
        self.rig = rig
        self.proj_shape = rig.projector.intrinsics.shape
        self.gamma = float(projector_gamma)
        self.blur = float(projector_blur)
        self.scene = TerrainScene(
            terrain,
            rig.camera,
            lights=[
                ProjectorLight(
                    rig.projector, np.ones(self.proj_shape, np.float32), scale=projector_scale
                ),
                *extra_lights,
            ],
            bsdf=bsdf,
            max_depth=max_depth,
            spp=spp,
            seed=seed,
        )
        self.rng = np.random.default_rng(rng)
        self.renders = 0
        # calibration frame (not counted as a scan render): sets the exposure
        white = self.scene.render_patterns(np.ones((1, *self.proj_shape), np.float32))[0]
        ref = float(np.percentile(white, EXPOSURE_PERCENTILE))
        if not ref > 0:
            raise ValueError(
                "the camera does not see the projected area: the white frame is "
                "black in the triangulation camera"
            )
        self.gain = target_level / ref
        self.sensor = None
        if sensor is not None:
            # electrons per unit radiance so that radiance * gain = 1 is the top of the ADC range
            self.sensor = dataclasses.replace(
                sensor, exposure=self.gain * sensor.max_dn * sensor.gain_e_per_dn
            )

    def emitted(self, patterns: np.ndarray) -> np.ndarray:
        """What the projector emits for digital patterns in [0, 1]: response then optics blur."""
        p = np.clip(np.asarray(patterns, np.float32), 0.0, 1.0) ** self.gamma
        if self.blur > 0:
            p = np.stack([ndimage.gaussian_filter(x, self.blur, mode="nearest") for x in p])
        return p

    def render(self, patterns) -> np.ndarray:
        """Noise-free luminance (n, rows, cols) under ``patterns`` (n, H, W)."""
        pats = np.asarray(patterns, np.float32)
        if pats.ndim != 3 or pats.shape[1:] != tuple(self.proj_shape):
            raise ValueError(
                f"patterns must have shape (n, {self.proj_shape[0]}, "
                f"{self.proj_shape[1]}) for this projector, got {pats.shape}"
            )
        self.renders += len(pats)
        return self.scene.render_patterns(self.emitted(pats)).astype(np.float64)

    def sense(self, images) -> np.ndarray:
        """Captured frames in [0, 1]-ish units: exposure, then sensor noise per frame."""
        imgs = np.asarray(images, np.float64)
        if self.sensor is None:
            return imgs * self.gain
        from simlunar.imaging.sensor import apply_sensor

        # one noise draw per captured frame (inverses by linearity included)
        return np.stack([apply_sensor(im, self.sensor, rng=self.rng) for im in imgs]).astype(
            np.float64
        )


@dataclass(frozen=True, eq=False)
class GuideView:
    """The co-located guide camera's image and ground truth.

    Attributes
    ----------
    image : (H, W) float64 luminance (planner input)
    depth : (H, W) float64 ground-truth z-depth (NaN off the terrain)
    valid : (H, W) bool
    """

    image: np.ndarray
    depth: np.ndarray
    valid: np.ndarray


def render_guide(
    terrain,
    rig: Rig,
    *,
    light: str = "projector",
    sun=None,
    bsdf=None,
    max_depth: int = 3,
    spp: int = 16,
    seed: int = 0,
) -> GuideView:
    """Render the guide image (projector all-white frame or sun) and its ground-truth depth.

    Parameters
    ----------
    light : "projector" or "sun"
        ``projector``: lit by the co-located projector's all-white frame, a camera-centred
        light, so no cast shadows are visible; ``sun``: lit by ``sun`` (a ``SunLight`` spec).
    """
    from simlunar.render.lights import ProjectorLight, SunLight
    from simlunar.render.scene import TerrainScene, luminance

    H, W = rig.projector.intrinsics.shape
    if light == "projector":
        lights = [ProjectorLight(rig.projector, np.ones((H, W), np.float32))]
    elif light == "sun":
        if not isinstance(sun, SunLight):
            raise ValueError("light='sun' needs sun=SunLight(...)")
        lights = [sun]
    else:
        raise ValueError(f"unknown guide light {light!r}; valid: 'projector', 'sun'")
    scene = TerrainScene(
        terrain, rig.guide, lights=lights, bsdf=bsdf, max_depth=max_depth, spp=spp, seed=seed
    )
    img = luminance(scene.render()).astype(np.float64)
    gt = scene.ground_truth()
    return GuideView(image=img, depth=np.asarray(gt.depth, float), valid=np.asarray(gt.valid))


def camera_truth(capture: RenderCapture, guide: GuideView) -> dict:
    """Ground truth in the triangulation camera: true projector column/row and projector light.

    Returns a dict with ``col``, ``row`` ((rows, cols) int, -1 where not lit) and ``lit``
    (the surface point each camera pixel sees is lit directly by the projector).
    """
    gt = capture.scene.ground_truth()
    lit = projector_visibility(gt.position, capture.rig.projector, guide.depth)
    col, row = true_correspondences(gt.position, capture.rig.projector, lit=lit)
    return {"col": col, "row": row, "lit": lit, "valid": np.asarray(gt.valid)}


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


def score_depth(
    depth: np.ndarray, truth: np.ndarray, *, metrics, image=None, mask=None
) -> dict[str, float]:
    """Sampling-study metrics of a reconstructed guide-view depth against ground truth.

    Parameters
    ----------
    depth, truth : (H, W) float64 z-depth (m); NaN in ``truth`` is excluded
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
    gray_opts: dict | None = None,
    dot_opts: dict | None = None,
    planner_opts: dict | None = None,
    progress=None,
) -> ScannerStudyResult:
    """Scan a terrain with a rig in several modes and score the guide-view depth.

    Parameters
    ----------
    terrain : Terrain
    rig : Rig (e.g. :func:`simlunar.scanner.rigs.moonyard_rig` aimed at the terrain)
    modes : names from :data:`simlunar.scanner.modes.MODES`
    planners : planner strategy names (:func:`simlunar.planner.plan`) for the dot modes
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
    gray_opts, dot_opts, planner_opts : options for the gray-code scan, dot scans, planners
    progress : callable(str) or None

    Returns
    -------
    ScannerStudyResult
    """
    unknown = [m for m in modes if m not in scan_modes.MODES]
    if unknown:
        raise ValueError(f"unknown scan mode(s) {unknown}; valid: {sorted(scan_modes.MODES)}")
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
            record("gray_code", "", 0, res, bit_error_table(gray, camera_truth(capture, guide)))
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
                    "planner_opts": planner_opts,
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
    spp: int = 8,
    max_depth: int = 3,
    sensor: bool = True,
    projector_blur: float = 0.0,
    metrics=("mse", "grad", "sal"),
    progress=None,
) -> list[dict]:
    """The paper's ambiguity-enhancement experiment (section 5) with plain arguments.

    Generates the terrain preset (``terrain_scale`` shrinks the grid), aims the rig preset at
    it, scans with full gray code and then rescans ``budget`` of the guide pixels with dots
    chosen by each planner, and returns tidy rows (see :func:`run_scanner_study`). With
    ``sensor`` a 12-bit sensor with shot and read noise captures every frame.
    """
    from simlunar.terrain import generate

    t_rng, s_rng = np.random.default_rng(seed).spawn(2)
    terr = generate(terrain, rng=t_rng, scale=terrain_scale).terrain
    rig = aim_rig_at_terrain(terr, preset=rig_preset, proj_size=proj_size, cam_size=cam_size)
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
