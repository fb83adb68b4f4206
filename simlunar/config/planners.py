"""Planner options of the schema: a strategy label's options (placement, density mapping,
feature maps, combination weights, the oracle's schedule, multi-round options) and the check of
which strategy takes which (shared by the sampling study and the scanner study's planners)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, PositiveInt, field_validator, model_validator

from simlunar.config.fields import _Model
from simlunar.features.maps import check_entropy_size

__all__ = [
    "FEATURE_OPTION_KEYS",
    "STRATEGY_OPTION_KEYS",
    "CoefficientsCfg",
    "FeatureOptsCfg",
    "OracleOptsCfg",
    "PlannerOptsCfg",
    "SequentialCfg",
    "StrategyOptionsCfg",
    "check_planner_options",
]


# Planner options. Defaults are the library's (a test compares them with the signatures of
# simlunar.planner / simlunar.features); the translation passes them to the weighted strategies.
#: the feature-map options each weighted strategy's map takes
FEATURE_OPTION_KEYS = {
    "uniform": (),
    "gradient": (),
    "saliency": (),
    "entropy": ("size", "scale"),
    "wavelet": ("wavelet", "levels", "boundary"),
    "learned": ("model",),
}


class FeatureOptsCfg(_Model):
    """Options of the strategy's importance map (:func:`simlunar.features.feature_map`).

    ``wavelet``, ``levels``, ``boundary`` belong to the wavelet map; ``size``, ``scale`` to the
    entropy map. A ``combination`` passes each map the options that belong to it.
    """

    wavelet: str = Field("db2", description="wavelet map: PyWavelets wavelet name")
    levels: PositiveInt | None = Field(
        None, description="wavelet map: decomposition levels summed, finest first; null = all"
    )
    boundary: Literal["symmetric", "periodic"] = Field("symmetric", description="wavelet map")
    size: PositiveInt = Field(9, description="entropy map: odd window side (px), 1..63")
    scale: Literal["minmax", "unit"] = Field("minmax", description="entropy map: 8-bit scaling")
    model: str | None = Field(
        None,
        description="learned map: model file (.joblib beside its .json, written by "
        "`simlunar train`), relative to the working folder",
    )

    @field_validator("model")
    @classmethod
    def _joblib(cls, v: str | None) -> str | None:
        if v is not None and not v.endswith(".joblib"):
            raise ValueError(f"a learned model file ends in .joblib, got {v!r}")
        return v

    @field_validator("size")
    @classmethod
    def _entropy_window(cls, v: int) -> int:
        check_entropy_size(v)  # the map's own rule
        return v

    @field_validator("wavelet")
    @classmethod
    def _known_wavelet(cls, v: str) -> str:
        import pywt

        if v not in pywt.wavelist(kind="discrete"):
            raise ValueError(f"unknown discrete wavelet {v!r} (e.g. db2, haar, sym4)")
        return v


class CoefficientsCfg(_Model):
    """``combination`` strategy: the weight of each feature map (maps normalised to mean 1;
    ``uniform`` is the constant map)."""

    uniform: float | None = Field(None, ge=0)
    gradient: float | None = Field(None, ge=0)
    entropy: float | None = Field(None, ge=0)
    wavelet: float | None = Field(None, ge=0)
    saliency: float | None = Field(None, ge=0)

    def as_mapping(self) -> dict[str, float]:
        return {k: v for k, v in self.model_dump().items() if v is not None}


class OracleOptsCfg(_Model):
    """``oracle_greedy`` only: the truth-driven refiner's schedule
    (:func:`simlunar.planner.oracle.oracle_greedy`)."""

    start_share: float = Field(0.25, gt=0, le=1, description="share of k in the framed grid")
    batch_share: float = Field(0.15, gt=0, description="batch, a share of the current count")
    smooth_pitch: float = Field(0.25, ge=0, description="error smoothing sigma (pitches)")
    nms_pitch: float = Field(1.0, gt=0, description="peak suppression window (pitches)")
    reconstruction: str = Field(
        "linear",
        min_length=1,
        description="whose true error the oracle feeds back: linear (the paper's) or a name "
        "or label of study.reconstructions (e.g. shading: the bound for the fused model)",
    )


#: maps a sequential strategy may take as its prior (none: the error estimate alone)
SEQUENTIAL_PRIORS = ("none", "wavelet", "gradient", "entropy", "saliency", "learned")


class SequentialCfg(_Model):
    """``sequential`` only: region-based iterative enhancement
    (:func:`simlunar.planner.sequential.plan_sequential`): a uniform first round, then batches
    where the measured samples' leave-one-out residuals say the surface is rough."""

    max_rounds: int = Field(12, ge=2, le=1000, description="sensor rounds cap, first included")
    first_share: float = Field(0.3, gt=0, lt=1, description="share of k in the first round")
    batch_share: float = Field(0.12, gt=0, le=1, description="samples per later round / k")
    temper: float = Field(0.5, gt=0, le=1, description="power of the smoothed residual^2")
    uniform_mix: float = Field(0.5, ge=0, le=1, description="uniform share of the estimate")
    prior_power: float = Field(0.5, gt=0, description="power of the prior map")
    nms_pitches: float = Field(0.7, gt=0, description="peak suppression radius (pitches)")
    prior: Literal["none", "wavelet", "gradient", "entropy", "saliency", "learned"] = Field(
        "none", description="image map multiplying the estimate (feature_opts are its options)"
    )
    first_round: Literal["uniform", "prior"] = Field(
        "uniform",
        description="first layout: uniform Lloyd, or the Lloyd layout of the prior map "
        "(prior^prior_power, 25 % uniform; needs a prior)",
    )

    @model_validator(mode="after")
    def _first_round_needs_a_prior(self):
        if self.first_round == "prior" and self.prior == "none":
            raise ValueError("first_round: 'prior' needs a prior map (sequential.prior)")
        return self


#: lloyd placement options (placement: lloyd, lloyd_uniform, oracle_hessian)
LLOYD_KEYS = ("lloyd_iterations", "border_pitch")
#: options that follow placement: random only / lloyd only
RANDOM_ONLY_KEYS = ("density_cap", "cap_block", "blue_noise", "blue_noise_radius")
#: the option keys each non-weighted strategy takes (weighted ones: all but oracle/sequential)
STRATEGY_OPTION_KEYS = {
    "grid": (),
    "random": (),
    "lloyd_uniform": LLOYD_KEYS,
    "oracle_greedy": ("oracle",),
    "oracle_hessian": ("density_power", "uniform_mix", *LLOYD_KEYS),
    "sequential": ("sequential", "feature_opts"),
}
#: uniform_mix when the YAML leaves it out, by placement (the library's defaults)
UNIFORM_MIX_DEFAULT = {"random": 0.0, "lloyd": 0.25}


class PlannerOptsCfg(_Model):
    """Options of a strategy (:func:`simlunar.planner.plan`).

    ``placement`` says how samples follow a weighted strategy's map: ``random`` (the paper's
    weighted random draw, paper parity) or ``lloyd`` (error-diffusion halftone of the density,
    weighted Lloyd relaxation, border covered). ``oracle`` holds ``oracle_greedy``'s schedule,
    ``sequential`` the multi-round options of ``sequential``.
    """

    placement: Literal["random", "lloyd"] = Field(
        "random", description="random: the paper's weighted draw; lloyd: halftone + Lloyd"
    )
    density_power: float | None = Field(
        None, gt=0, description="power of the map; null = 1 (random) or 1/2 (lloyd)"
    )
    uniform_mix: float = Field(
        0.0, ge=0, le=1, description="mixture with uniform; left out = 0 (random), 0.25 (lloyd)"
    )
    lloyd_iterations: int = Field(20, ge=0, le=1000, description="lloyd: relaxation steps")
    border_pitch: float | None = Field(
        0.75, ge=0, description="lloyd: snap samples this many pitches from the border onto it"
    )
    density_cap: float | None = Field(
        None, ge=1, description="max regional density, a multiple of the mean; null = none"
    )
    cap_block: PositiveInt = Field(16, description="block side (px) of density_cap")
    blue_noise: bool = Field(False, description="Poisson-disk-like weighted sampling")
    blue_noise_radius: float = Field(0.5, gt=0, description="radius factor of blue_noise")
    feature_opts: FeatureOptsCfg = Field(default_factory=FeatureOptsCfg)
    coefficients: CoefficientsCfg = Field(
        default_factory=CoefficientsCfg, description="combination only: map weights"
    )
    oracle: OracleOptsCfg = Field(
        default_factory=OracleOptsCfg, description="oracle_greedy only: its schedule"
    )
    sequential: SequentialCfg = Field(
        default_factory=SequentialCfg, description="sequential only: rounds and estimate"
    )

    @model_validator(mode="before")
    @classmethod
    def _mix_of_placement(cls, data):
        # the library's uniform share depends on the placement: fill it in when left out
        if isinstance(data, dict) and "uniform_mix" not in data:
            mix = UNIFORM_MIX_DEFAULT.get(data.get("placement", "random"))
            if mix:
                data = {**data, "uniform_mix": mix}
        return data


class StrategyOptionsCfg(PlannerOptsCfg):
    """A strategy label's options: ``strategy`` names the registered strategy (default: the
    label itself), the rest are its planner options."""

    strategy: str | None = Field(None, description="registered strategy; null = the label")


def _changed(opts: _Model, default: _Model) -> list[str]:
    return [k for k in type(default).model_fields if getattr(opts, k) != getattr(default, k)]


def check_planner_options(base: str, opts: PlannerOptsCfg) -> None:
    """Raise ``ValueError("<key>: problem")`` for options the strategy ``base`` does not take."""
    default = PlannerOptsCfg(placement=opts.placement)
    changed = [k for k in _changed(opts, default) if k != "strategy"]
    if opts.placement != "random":
        changed.insert(0, "placement")
    if base in STRATEGY_OPTION_KEYS:
        bad = [k for k in changed if k not in STRATEGY_OPTION_KEYS[base]]
        if bad and not STRATEGY_OPTION_KEYS[base]:
            raise ValueError(f"{bad[0]}: strategy {base!r} takes no options")
        if bad:
            valid = ", ".join(STRATEGY_OPTION_KEYS[base])
            raise ValueError(f"{bad[0]}: not an option of strategy {base!r} (valid: {valid})")
        features = [opts.sequential.prior] if base == "sequential" else []
        _check_feature_opts(opts.feature_opts, [f for f in features if f != "none"])
        return
    for key in ("oracle", "sequential"):
        if key in changed:
            raise ValueError(f"{key}: only the {key}{'_greedy' * (key == 'oracle')} strategy "
                             f"takes it ({base!r})")  # fmt: skip
    wrong = RANDOM_ONLY_KEYS if opts.placement == "lloyd" else LLOYD_KEYS
    for k in changed:
        if k in wrong:
            need = "random" if opts.placement == "lloyd" else "lloyd"
            raise ValueError(f"{k}: needs placement: {need} (strategy {base!r})")
    if base == "combination":
        if not opts.coefficients.as_mapping():
            raise ValueError("coefficients: strategy 'combination' needs at least one weight")
        features = list(opts.coefficients.as_mapping())
    else:
        if "coefficients" in changed:
            raise ValueError(f"coefficients: only the combination strategy takes them ({base!r})")
        features = [base]
    _check_feature_opts(opts.feature_opts, features)


def _check_feature_opts(fo: FeatureOptsCfg, features: list[str]) -> None:
    allowed = {k for f in features for k in FEATURE_OPTION_KEYS.get(f, ())}
    for k in _changed(fo, FeatureOptsCfg()):
        if k not in allowed:
            raise ValueError(
                f"feature_opts.{k}: not an option of the {'/'.join(features) or 'no'} map "
                f"(valid: {', '.join(sorted(allowed)) or 'none'})"
            )
    if "learned" in features and fo.model is None:
        raise ValueError("feature_opts.model: the learned map needs its model file (.joblib)")
