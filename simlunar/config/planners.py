"""Planner options of the schema, derived from the registries: a strategy label's options
(placement, density mapping, feature maps, combination weights, the oracle's schedule,
multi-round options) and the check of which strategy takes which (shared by the sampling
study and the scanner and LIDAR studies' planners).

Nothing here lists a planner, a placement or a map: the YAML keys are the fields of the options
classes of :data:`simlunar.planner.PLACEMENTS`, :data:`simlunar.planner.PLANNERS` and
:data:`simlunar.features.MAPS` (:func:`simlunar.config.derived.options_model`), and which
planner takes which key is read from the entries (:func:`check_planner_options`). A planner or
map registered later (a test's, a plug-in's) is usable from YAML with no edit here.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Mapping
from typing import Annotated, Any, Literal

from pydantic import (
    BeforeValidator,
    Field,
    create_model,
    field_validator,
    model_serializer,
    model_validator,
)

from simlunar.config.derived import options_model
from simlunar.config.fields import _Model
from simlunar.features import MAPS
from simlunar.planner import PLACEMENTS, PLANNERS, MapSource
from simlunar.planner.registry import COMBINATION, combinable, field_names

__all__ = [
    "CoefficientsCfg",
    "FeatureOptsCfg",
    "OracleOptsCfg",
    "PlannerOptions",
    "PlannerOptsCfg",
    "SequentialCfg",
    "StrategyOptions",
    "StrategyOptionsCfg",
    "check_planner_options",
    "effective_placement",
    "feature_keys",
    "own_placements",
    "section_models",
]


def feature_keys(name: str) -> tuple[str, ...]:
    """The YAML ``feature_opts`` keys of map ``name`` (its options less the ones the planner
    sets at run time, e.g. the learned map's density); none for ``uniform`` or an unknown map."""
    if name not in MAPS:
        return ()
    runtime = MAPS[name].meta.get("runtime", ())
    return tuple(k for k in field_names(MAPS[name].options) if k not in runtime)


def _merged(classes, *, what: str) -> dict[str, tuple[Any, Any]]:
    """name -> (annotation, FieldInfo) of the fields of several options classes: the first
    declaration of a name wins; a later one must agree on its bounds and choices."""
    out: dict[str, tuple[Any, Any]] = {}
    rules: dict[str, tuple] = {}
    for cls, skip in classes:
        model = options_model(cls)
        for name, info in model.model_fields.items():
            if name in skip:
                continue
            meta = dataclasses.fields(cls)[field_names(cls).index(name)].metadata
            rule = tuple(meta.get(k) for k in ("ge", "gt", "le", "lt", "choices"))
            if name in out:
                if rules[name] != rule:
                    raise TypeError(f"{what} option {name!r} is declared twice with other bounds")
                continue
            out[name], rules[name] = (info.annotation, copy.copy(info)), rule
    return out


# ---- feature_opts: the options of every map, one flat section ---------------------------------
def _owners() -> dict[str, list[str]]:
    owners: dict[str, list[str]] = {}
    for name in MAPS:
        for key in feature_keys(name):
            owners.setdefault(key, []).append(name)
    return owners


class _FeatureOptsBase(_Model):
    """Options of the strategy's importance map (:func:`simlunar.features.feature_map`); each
    key belongs to the maps whose options class declares it, and a ``combination`` passes each
    map the keys that belong to it."""

    @model_serializer(mode="wrap")
    def _without_new_defaults(self, handler):
        # the options of a map registered after the cache keys were fixed are left out at their
        # defaults (results/cache_keys.py), so adding a map keeps every earlier cache valid
        data = handler(self)
        if isinstance(data, dict):
            for key, maps in _owners().items():
                if key in data and not any(MAPS[m].meta.get("cache_defaults") for m in maps):
                    if data[key] == type(self).model_fields[key].default:
                        del data[key]
        return data


def _map_rule(key: str):
    """A field validator: the value through the options class of every map that declares
    ``key`` (the map's own rule, e.g. an odd entropy window)."""

    def check(cls, v):
        for m in _owners().get(key, ()):
            MAPS[m].options(**{key: v})
        return v

    return field_validator(key)(classmethod(check))


_FEATURE_FIELDS = _merged(
    [(MAPS[n].options, MAPS[n].meta.get("runtime", ())) for n in MAPS], what="map"
)
FeatureOptsCfg = create_model(
    "FeatureOptsCfg",
    __base__=_FeatureOptsBase,
    __doc__=_FeatureOptsBase.__doc__,
    __validators__={f"_rule_{k}": _map_rule(k) for k in _FEATURE_FIELDS},
    **_FEATURE_FIELDS,
)


# ---- coefficients: one weight per combinable map ----------------------------------------------
class _CoefficientsBase(_Model):
    """``combination`` strategy: the weight of each feature map (maps normalised to mean 1;
    ``uniform`` is the constant map)."""

    def as_mapping(self) -> dict[str, float]:
        return {k: v for k, v in self.model_dump().items() if v is not None}


CoefficientsCfg = create_model(
    "CoefficientsCfg",
    __base__=_CoefficientsBase,
    __doc__=_CoefficientsBase.__doc__,
    **{n: (float | None, Field(None, ge=0)) for n in combinable()},
)


# ---- sections: a planner's options under a YAML key of their own -----------------------------
def section_models() -> dict[str, tuple[str, type]]:
    """YAML section -> (planner, derived model) of the planners registered with ``section``
    (``oracle``: the greedy oracle's schedule); the measuring planner's section is
    :class:`SequentialCfg`."""
    return {
        e.meta["section"]: (n, options_model(e.options, f"{n} options"))
        for n, e in PLANNERS.items()
        if e.meta.get("section") and not e.meta.get("measuring")
    }


OracleOptsCfg = section_models()["oracle"][1]


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
    prior: Literal[("none", *MAPS)] = Field(  # type: ignore[valid-type]
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


# ---- the planner options: placement, the placements' and planners' options, the sections ------
_DEFAULT_PLACEMENT = next(iter(PLACEMENTS))


def _top_level_classes():
    """Options classes whose fields are top-level YAML keys: every placement's, then every
    function planner's without a section of its own."""
    out = [(PLACEMENTS[p].options, ()) for p in PLACEMENTS]
    for e in PLANNERS.values():
        if not isinstance(e.target, MapSource) and not e.meta.get("section"):
            out.append((e.options, ()))
    return out


def _placement_defaults(placement: str) -> dict[str, Any]:
    """The library defaults of a placement's options that differ from the YAML's."""
    fields = PlannerOptsCfg.model_fields
    return {
        f.name: f.default
        for f in dataclasses.fields(PLACEMENTS[placement].options)
        if f.name in fields and f.default != fields[f.name].default
    }


class _PlannerOptsBase(_Model):
    """Options of a strategy (:func:`simlunar.planner.plan`).

    ``placement`` says how samples follow a map planner's map: ``random`` (the paper's
    weighted random draw, paper parity; the default keeps a planner's own placement, e.g.
    ``wavelet_lloyd``'s) or ``lloyd`` (error-diffusion halftone of the density, weighted Lloyd
    relaxation, border covered). ``oracle`` holds ``oracle_greedy``'s schedule, ``sequential``
    the multi-round options of ``sequential``.
    """

    @model_validator(mode="before")
    @classmethod
    def _defaults_of_placement(cls, data):
        # a placement's own defaults (uniform_mix 0.25 for lloyd) fill the keys left out
        if isinstance(data, dict) and data.get("placement", _DEFAULT_PLACEMENT) in PLACEMENTS:
            fill = _placement_defaults(data.get("placement", _DEFAULT_PLACEMENT))
            data = {**fill, **data}
        return data


def _planner_fields() -> dict[str, tuple[Any, Any]]:
    fields: dict[str, tuple[Any, Any]] = {
        "placement": (
            Literal[tuple(PLACEMENTS)],
            Field(
                _DEFAULT_PLACEMENT,
                description="; ".join(f"{n}: {e.summary}" for n, e in PLACEMENTS.items()),
            ),
        )
    }
    fields.update(_merged(_top_level_classes(), what="planner"))
    fields["feature_opts"] = (FeatureOptsCfg, Field(default_factory=FeatureOptsCfg))
    fields["coefficients"] = (
        CoefficientsCfg,
        Field(default_factory=CoefficientsCfg, description="combination only: map weights"),
    )
    for section, (name, model) in section_models().items():
        fields[section] = (model, Field(default_factory=model, description=f"{name} only"))
    fields["sequential"] = (
        SequentialCfg,
        Field(default_factory=SequentialCfg, description="sequential only: rounds and estimate"),
    )
    return fields


PlannerOptsCfg = create_model(
    "PlannerOptsCfg", __base__=_PlannerOptsBase, __doc__=_PlannerOptsBase.__doc__,
    **_planner_fields(),
)  # fmt: skip


class StrategyOptionsCfg(PlannerOptsCfg):  # type: ignore[misc, valid-type]
    """A strategy label's options: ``strategy`` names the registered strategy (default: the
    label itself), the rest are its planner options."""

    strategy: str | None = Field(None, description="registered strategy; null = the label")


def own_placements(value):
    """``label -> options`` with each map planner's own placement filled in where the YAML
    leaves ``placement`` out (so ``wavelet_lloyd: {uniform_mix: 0}`` is a Lloyd layout with
    no uniform share, and its dump names the placement); any other value unchanged."""
    if not isinstance(value, Mapping):
        return value
    out = {}
    for label, opts in value.items():
        base = opts.get("strategy") or label if isinstance(opts, Mapping) else None
        if base in PLANNERS and "placement" not in opts:
            source = PLANNERS[base].target
            if isinstance(source, MapSource) and source.placement != _DEFAULT_PLACEMENT:
                opts = {**opts, "placement": source.placement}
        out[label] = opts
    return out


#: ``label -> options`` of a study's planners (the placement of a map planner filled in)
PlannerOptions = Annotated[dict[str, PlannerOptsCfg], BeforeValidator(own_placements)]
#: ``label -> options`` of the sampling study's strategies (``strategy`` may name the planner)
StrategyOptions = Annotated[dict[str, StrategyOptionsCfg], BeforeValidator(own_placements)]


# ---- which planner takes which key: read from the entries ------------------------------------
def effective_placement(base: str, opts) -> str:
    """The placement a map planner uses: the YAML's, or the planner's own when the YAML leaves
    the default (``wavelet_lloyd`` is placed by Lloyd unless told otherwise)."""
    source = PLANNERS[base].target
    if opts.placement != _DEFAULT_PLACEMENT or not isinstance(source, MapSource):
        return opts.placement
    return source.placement


def _changed(opts, default) -> list[str]:
    return [k for k in type(default).model_fields if getattr(opts, k) != getattr(default, k)]


def _sections() -> dict[str, str]:
    """YAML section -> the planner that takes it."""
    return {e.meta["section"]: n for n, e in PLANNERS.items() if e.meta.get("section")}


def check_planner_options(base: str, opts) -> None:
    """Raise ``ValueError("<key>: problem")`` for options the strategy ``base`` does not take."""
    entry = PLANNERS[base]
    default = PlannerOptsCfg(placement=opts.placement)
    changed = [k for k in _changed(opts, default) if k != "strategy"]
    if opts.placement != _DEFAULT_PLACEMENT:
        changed.insert(0, "placement")
    if not isinstance(entry.target, MapSource):
        section = entry.meta.get("section")
        allowed = (section,) if section else field_names(entry.options)
        if entry.meta.get("measuring"):
            allowed = (*allowed, "feature_opts")
        bad = [k for k in changed if k not in allowed]
        if bad and not allowed:
            raise ValueError(f"{bad[0]}: strategy {base!r} takes no options")
        if bad:
            valid = ", ".join(allowed)
            raise ValueError(f"{bad[0]}: not an option of strategy {base!r} (valid: {valid})")
        prior = [opts.sequential.prior] if entry.meta.get("measuring") else []
        _check_feature_opts(opts.feature_opts, [f for f in prior if f != "none"])
        return
    for key, owner in _sections().items():
        if key in changed:
            raise ValueError(f"{key}: only the {owner} strategy takes it ({base!r})")
    placement = effective_placement(base, opts)
    mine = field_names(PLACEMENTS[placement].options)
    for k in changed:
        if k in ("placement", "feature_opts", "coefficients") or k in mine:
            continue
        need = [p for p in PLACEMENTS if k in field_names(PLACEMENTS[p].options)]
        if need:
            raise ValueError(f"{k}: needs placement: {need[0]} (strategy {base!r})")
        raise ValueError(f"{k}: not an option of strategy {base!r}")
    if entry.target.map == COMBINATION:
        if not opts.coefficients.as_mapping():
            raise ValueError(f"coefficients: strategy {base!r} needs at least one weight")
        features = list(opts.coefficients.as_mapping())
    else:
        if "coefficients" in changed:
            raise ValueError(f"coefficients: only the combination strategy takes them ({base!r})")
        features = [entry.target.map]
    _check_feature_opts(opts.feature_opts, features)


def _check_feature_opts(fo, features: list[str]) -> None:
    allowed = {k for f in features for k in feature_keys(f)}
    for k in _changed(fo, FeatureOptsCfg()):
        if k not in allowed:
            raise ValueError(
                f"feature_opts.{k}: not an option of the {'/'.join(features) or 'no'} map "
                f"(valid: {', '.join(sorted(allowed)) or 'none'})"
            )
    for f in features:
        if f in MAPS and MAPS[f].meta.get("needs_model") and fo.model is None:
            raise ValueError(f"feature_opts.model: the {f} map needs its model file (.joblib)")
