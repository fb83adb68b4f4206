"""Configuration -> library objects of the scanner study: the rig's keywords in radians and
metres, the codings' and the dot scan's options, the capture options and the study's options
(the rest of the translation is :mod:`simlunar.config.translate`)."""

from __future__ import annotations

import math
from typing import Any

from simlunar.config.derived import reconstruction_mapping
from simlunar.config.fields import library_values
from simlunar.config.render import RenderCfg, SunLightCfg
from simlunar.config.scanner import CODING_OPTS, DotOptsCfg, RigCfg, ScannerStudyCfg
from simlunar.config.translate import lights, planner_kwargs
from simlunar.imaging.projector_optics import ProjectorOptics
from simlunar.render.capture import CaptureOptions
from simlunar.scanner.codings import CODINGS
from simlunar.scanner.dot_scan import DotOptions
from simlunar.study.scanner import ScannerStudyOptions

__all__ = [
    "capture_options",
    "coding_options",
    "dot_options",
    "rig_kwargs",
    "scanner_guide_frames",
    "scanner_options",
]


def rig_kwargs(study: ScannerStudyCfg) -> dict[str, Any]:
    """Keywords of :func:`simlunar.study.scanner.aim_rig_at_terrain` (radians, metres)."""
    r: RigCfg = study.options.rig
    kw: dict[str, Any] = {
        "preset": study.rig,
        "proj_size": tuple(study.projector_px),
        "cam_size": tuple(study.camera_px),
        "fill": r.fill,
        "verge": r.verge,
        "aperture_radius": r.aperture_radius_m,
    }
    angles = {
        "fov_x": r.fov_x_deg,
        "cam_fov_x": r.cam_fov_x_deg,
        "elevation": r.elevation_deg,
        "azimuth": r.azimuth_deg,
    }
    kw.update({k: math.radians(v) for k, v in angles.items() if v is not None})
    lengths = {
        "distance": r.distance_m,
        "altitude": r.altitude_m,
        "baseline": r.baseline_m,
        "focus_distance": r.focus_distance_m,
    }
    kw.update({k: v for k, v in lengths.items() if v is not None})
    return kw


def coding_options(opts) -> dict[str, Any]:
    """Coding name -> its options object (:data:`simlunar.scanner.codings.CODINGS`) from the
    coding blocks of a scanner study's ``options`` (``gray_opts``, ``phase_opts``, ...)."""
    return {
        name: CODINGS[name].options(**library_values(getattr(opts, key)))
        for name, (key, _model) in CODING_OPTS.items()
    }


def dot_options(opts: DotOptsCfg) -> DotOptions:
    """:class:`~simlunar.scanner.dot_scan.DotOptions` of a config (``_px`` suffixes dropped)."""
    return DotOptions(**{k.removesuffix("_px"): v for k, v in opts.model_dump().items()})


def capture_options(study: ScannerStudyCfg, render: RenderCfg, seed: int) -> CaptureOptions:
    """:class:`~simlunar.render.capture.CaptureOptions` of a scanner study and its render
    section (``seed``: the sampler seed of the unit's render stage)."""
    return CaptureOptions(
        max_depth=render.max_depth,
        spp=render.spp,
        seed=seed,
        projector_gamma=study.projector_gamma,
        projector_blur=study.projector_blur_px,
        camera_blur=study.camera_blur_px,
        optics=None
        if study.projector_optics is None
        else ProjectorOptics(**library_values(study.projector_optics)),
        **study.options.capture_opts.model_dump(),
    )


def scanner_options(
    study: ScannerStudyCfg, render: RenderCfg, *, seed: int = 0
) -> ScannerStudyOptions:
    """:class:`~simlunar.study.scanner.ScannerStudyOptions` of a config (the rig is built by
    :func:`rig_kwargs`); ``save_scans`` keeps the coded scan's frames the export needs."""
    o = study.options
    return ScannerStudyOptions(
        modes=tuple(study.modes),
        planners=tuple(study.planners),
        budget=study.budget,
        trials=study.trials,
        metrics=tuple(study.metrics),
        guide_light=study.guide_light,
        capture=capture_options(study, render, seed),
        coding=study.coding,
        codings=coding_options(o),
        keep_frames=study.save_scans,
        dots=dot_options(o.dot_opts),
        planner_opts={name: planner_kwargs(name, p) for name, p in o.planner_opts.items()},
        reconstructions=reconstruction_mapping(study.reconstructions),
        guide_frames=scanner_guide_frames(render),
    )


def scanner_guide_frames(render: RenderCfg) -> tuple:
    """``render.guide_frames`` as the scanner study takes them: ``"camera"`` (the projector's
    flood frame) or the SunLight spec of another sun."""
    out = []
    for f in render.guide_frames:
        if isinstance(f, str):
            out.append(f)
        else:
            s = f.sun
            cfg = SunLightCfg(
                elevation_deg=s.elevation_deg, azimuth_deg=s.azimuth_deg, irradiance=s.irradiance
            )
            out.append(lights(cfg, 0.0)[0])
    return tuple(out)
