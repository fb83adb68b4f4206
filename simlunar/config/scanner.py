"""Scanner study section of the schema: the rig, coding, dot and capture options and the
structured-light study (paper section 5).

The options block of each coding (``options.gray_opts``, ``options.phase_opts``, ...) is
derived from the coding's registered options class (:data:`simlunar.scanner.codings.CODINGS`,
the entry's ``yaml_key``): its fields declared with :func:`simlunar.registry.option`, their
defaults, bounds, choices and docs; a new coding needs no edit here.
"""

from __future__ import annotations

from typing import Literal

from pydantic import (
    Field,
    PositiveInt,
    create_model,
    field_validator,
    model_validator,
)

from simlunar.config.fields import (
    Deg,
    Density,
    Metres,
    Px,
    PxCount,
    _Model,
    options_model,
    unique_names,
)
from simlunar.config.render import MAX_SPP
from simlunar.config.studies import (
    PlannerOptions,
    PlannerOptsCfg,
    Reconstructions,
    _reconstructions_field,
    check_planner_options,
)
from simlunar.imaging.projector_optics import ProjectorOptics
from simlunar.planner import DEFAULT_PLANNER, STRATEGIES
from simlunar.scanner.codings import CODINGS, DEFAULT_CODING, full_field_codings
from simlunar.scanner.rescan import SCAN_PLANNERS
from simlunar.scanner.scheduling import check_spacings
from simlunar.sensors.structured_light import MODES, mode_coding

__all__ = [
    "CODING_OPTS",
    "CaptureOptsCfg",
    "DotOptsCfg",
    "ProjectorOpticsCfg",
    "RigCfg",
    "ScannerOptionsCfg",
    "ScannerStudyCfg",
]


class RigCfg(_Model):
    """Adjustments of the rig preset (:mod:`simlunar.scanner.rigs`); null = the preset's."""

    fill: float = Field(
        0.9,
        ge=0.01,
        le=1,
        description="projection footprint / terrain side (0.01 .. 1: a smaller footprint puts "
        "the projector inside the terrain's relief)",
    )
    fov_x_deg: Deg | None = Field(
        None,
        gt=0,
        le=120,
        description="projector horizontal field of view (50 moonyard, 30 aerial; at most 120: "
        "a pinhole wider than that spreads its pixels over a grazing, useless rim)",
    )
    cam_fov_x_deg: Deg | None = Field(
        None,
        gt=0,
        le=120,
        description="triangulation camera field of view (at most 120); null = projector's",
    )
    distance_m: Metres | None = Field(
        None, gt=0, description="moonyard: projector standoff; null = fit the terrain"
    )
    altitude_m: Metres | None = Field(
        None, gt=0, description="aerial: projector altitude; null = fit the terrain"
    )
    elevation_deg: Deg | None = Field(
        None, gt=0, le=90, description="moonyard: projector elevation (default 70)"
    )
    azimuth_deg: Deg | None = Field(None, ge=-360, le=360, description="projector azimuth")
    baseline_m: Metres | None = Field(
        None, gt=0, description="camera offset; null = 0.25 (moonyard) / 0.15 (aerial) x standoff"
    )
    verge: bool = Field(True, description="camera verged on the target")
    aperture_radius_m: Metres = Field(0.0, ge=0, description="camera thin lens; 0 = pinhole")
    focus_distance_m: Metres | None = Field(None, gt=0, description="null = the target")

    @model_validator(mode="after")
    def _focus_needs_lens(self) -> RigCfg:
        if self.aperture_radius_m == 0 and self.focus_distance_m is not None:
            raise ValueError(
                "focus_distance_m: has no effect on a pinhole camera (aperture_radius_m 0); "
                "set aperture_radius_m > 0 for a thin lens or leave focus_distance_m null"
            )
        return self


#: coding name -> (YAML key under study.options, its derived options model)
CODING_OPTS = {
    n: (
        e.meta["yaml_key"],
        options_model(e.options, f"{e.options.__name__}Cfg", f"{e.summary} options"),
    )
    for n, e in CODINGS.items()
}


#: the projector optics block (``study.projector_optics``), derived from its options class
ProjectorOpticsCfg = options_model(
    ProjectorOptics, "ProjectorOpticsCfg", "The projector's optics (docs/scanner.md)."
)


class DotOptsCfg(_Model):
    """Dot scan options (:func:`simlunar.scanner.dot_scan.dot_scan`)."""

    exact: bool = Field(False, description="one dot per frame (reference mode)")
    radius_px: Px = Field(0.0, description="dot radius (projector px); 0 = one pixel")
    min_proj_spacing_px: Px = Field(8.0, description="scheduling spacing (projector px)")
    min_cam_spacing_px: Px = Field(6.0, description="scheduling spacing (camera px)")
    tol_px: Px = Field(2.0, description="matching tolerance (camera px)")
    rel_threshold: float = Field(0.02, ge=0, le=1, description="relative blob threshold")
    abs_threshold: float = Field(0.02, ge=0, le=1, description="absolute blob threshold")
    batch: PositiveInt = Field(8, description="frames per render call (memory only)")

    @model_validator(mode="after")
    def _spacings(self) -> DotOptsCfg:

        try:
            check_spacings(
                self.min_cam_spacing_px, self.min_proj_spacing_px
            )  # the scheduler's rule
        except ValueError:
            zero = "min_proj_spacing_px" if self.min_proj_spacing_px <= 0 else "min_cam_spacing_px"
            raise ValueError(f"{zero}: scheduling spacings must be > 0 px") from None
        return self


class CaptureOptsCfg(_Model):
    """Render-capture options (:class:`simlunar.render.capture.RenderCapture`)."""

    sparse_integrator: Literal["path", "ptracer", "lit"] = Field(
        "path",
        description="integrator for sparse patterns (dot frames): path tracer, ptracer "
        "(Mitsuba's light tracer, paths per camera pixel) or lit (paths per lit projector "
        "pixel: a dot frame costs what its dots cost; docs/scanner.md)",
    )
    sparse_spp: PositiveInt | None = Field(
        None, le=MAX_SPP, description="samples per pixel for sparse patterns (null: render.spp)"
    )
    sparse_below: float = Field(
        0.01, gt=0, le=1, description="largest lit fraction of projector pixels counted sparse"
    )
    sparse_particles: PositiveInt = Field(
        256, description="lit only: light paths per lit projector pixel (at pattern value 1)"
    )


ScannerOptionsCfg = create_model(
    "ScannerOptionsCfg",
    __base__=_Model,
    __doc__="Scanner study options: rig adjustments, each coding's options, dot scan and "
    "capture options, planner options.",
    rig=(RigCfg, Field(default_factory=RigCfg)),
    **{
        key: (model, Field(default_factory=model, description=CODINGS[n].summary))
        for n, (key, model) in CODING_OPTS.items()
    },
    dot_opts=(DotOptsCfg, Field(default_factory=DotOptsCfg)),
    capture_opts=(CaptureOptsCfg, Field(default_factory=CaptureOptsCfg)),
    planner_opts=(
        PlannerOptions,
        Field(default_factory=dict, description="planner name -> options (study.planners only)"),
    ),
)


class ScannerStudyCfg(_Model):
    """The structured-light scanner study of the paper's section 5
    (:func:`simlunar.study.scanner.run_scanner_study`)."""

    kind: Literal["scanner"]
    modes: list[str] = Field(
        default_factory=lambda: [DEFAULT_CODING, "ambiguity_enhancement"],
        min_length=1,
        description="scan modes: a full-field coding's name (a full scan with it: "
        f"{', '.join(full_field_codings())}), ambiguity_enhancement (the coding of "
        "study.coding, then dot rescans), data_reduction (dots only)",
    )
    coding: Literal[full_field_codings()] = Field(  # type: ignore[valid-type]
        DEFAULT_CODING,
        description="the full-field coding ambiguity enhancement rescans (and low_contrast ranks)",
    )
    planners: list[str] = Field(
        default_factory=lambda: [DEFAULT_PLANNER, "random"],
        min_length=1,
        description="what picks the dots (dot modes): a planner strategy (from the guide "
        "image) or low_contrast (the gray-code pixels the projector lit least; "
        "ambiguity_enhancement only)",
    )
    budget: Density = Field(0.1, description="fraction of guide pixels rescanned / sampled")
    trials: int = Field(1, ge=1, le=100)
    metrics: list[str] = Field(default_factory=lambda: ["mse", "grad", "sal"], min_length=1)
    rig: Literal["moonyard", "aerial"] = Field("moonyard", description="rig preset")
    projector_px: tuple[PxCount, PxCount] = Field(
        (256, 192), description="projector (width, height)"
    )
    camera_px: tuple[PxCount, PxCount] = Field((256, 192), description="camera (width, height)")
    guide_light: Literal["projector", "sun"] = Field(
        "projector", description="guide image light: camera-centred projector or render.light"
    )
    scan_light: Literal["none", "sun"] = Field(
        "none",
        description="light on during the scan besides the projector: none (a dark scan, as in "
        "the paper's lab) or sun (render.light, which must be a sun, and "
        "render.ambient_radiance stay on: a daylight scan; docs/scanner.md)",
    )
    projector_gamma: float = Field(1.0, gt=0, le=10, description="projector response exponent")
    projector_blur_px: Px = Field(
        0.0,
        description="projector defocus sigma (px; '1 px' or 1; at most a quarter of the "
        "projector's smaller side)",
    )
    camera_blur_px: Px = Field(
        0.0,
        description="camera lens point-spread function, Gaussian sigma (camera px; '1 px' or "
        "1; at most a quarter of the camera's smaller side)",
    )
    projector_optics: ProjectorOpticsCfg | None = Field(
        None,
        description="the projector's optics forming every pattern at sub-pixel resolution "
        "(response and pre-compensation, pixel fill factor, lens PSF, thin-lens defocus; "
        "defaults: a TI DLP5500 projector; docs/scanner.md); null: each pattern is its pixel "
        "grid through projector_gamma and projector_blur_px",
    )
    options: ScannerOptionsCfg = Field(
        default_factory=ScannerOptionsCfg,
        description="rig adjustments (rig), each coding's options "
        f"({', '.join(k for k, _ in CODING_OPTS.values())}), dot_opts, planner_opts",
    )
    save_scans: bool = Field(
        False,
        description="write scans/unit<i>/<coding>/ per unit and full-field coding: the coded "
        "scan's frames (8/16-bit PNG, OpenCV order), decoded maps and phase maps (EXR), point "
        "cloud (PLY), OpenCV calibration (docs/scanner.md)",
    )
    reconstructions: Reconstructions = _reconstructions_field()

    _unique = field_validator("modes", "planners", "metrics")(unique_names)

    @model_validator(mode="after")
    def _scans_need_a_coded_scan(self):
        coded = [m for m in self.modes if m in MODES and mode_coding(m, self.coding)]
        if self.save_scans and not coded:
            raise ValueError(
                "save_scans exports the full-field coded scan: modes must include one of "
                f"{', '.join(full_field_codings())} or ambiguity_enhancement"
            )
        return self

    @model_validator(mode="after")
    def _one_projector_model(self):
        if self.projector_optics is not None and (
            self.projector_gamma != 1.0 or self.projector_blur_px != 0.0
        ):
            raise ValueError(
                "projector_optics: replaces projector_gamma and projector_blur_px (leave them "
                "at 1 and 0; the optics have gamma and psf_sigma)"
            )
        return self

    @model_validator(mode="after")
    def _blur_fits(self):
        # a blur of a quarter of the image smears every stripe and dot over the whole frame
        for key, px in (
            ("projector_blur_px", self.projector_px),
            ("camera_blur_px", self.camera_px),
        ):
            sigma, most = getattr(self, key), min(px) / 4
            if sigma > most:
                raise ValueError(
                    f"{key}: {sigma:g} px blurs the pattern over the whole "
                    f"{px[0]} x {px[1]} image (at most {most:g} px, a quarter of its smaller side)"
                )
        return self

    @model_validator(mode="after")
    def _options_fit(self) -> ScannerStudyCfg:

        o = self.options
        stray = sorted(set(o.planner_opts) - set(self.planners))
        if stray:
            raise ValueError(
                f"options.planner_opts.{stray[0]}: not in study.planners ({', '.join(self.planners)})"
            )

        scan_planners = [p for p in self.planners if p in SCAN_PLANNERS]
        if scan_planners and "data_reduction" in self.modes:
            raise ValueError(
                f"planners: {scan_planners[0]} ranks the pixels of the "
                f"{self.coding.replace('_', '-')} scan, which "
                "the data_reduction mode does not make (use it with ambiguity_enhancement)"
            )
        for name in scan_planners:
            if name in o.planner_opts:
                raise ValueError(f"options.planner_opts.{name}: {name} takes no options")
        for name in self.planners:
            opts = o.planner_opts.get(name)
            if name in STRATEGIES:
                try:
                    check_planner_options(name, opts or PlannerOptsCfg())
                except ValueError as exc:
                    where = (
                        f"options.planner_opts.{name}" if opts is not None else f"planners ({name})"
                    )
                    raise ValueError(f"{where}.{exc}") from None
        moonyard_only = ("distance_m", "elevation_deg")
        aerial_only = ("altitude_m",)
        for key in aerial_only if self.rig == "moonyard" else moonyard_only:
            if getattr(o.rig, key) is not None:
                raise ValueError(f"options.rig.{key}: not an option of the {self.rig} rig")
        return self
