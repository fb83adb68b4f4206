"""The training YAML of the learned importance map or learned reconstruction (``simlunar train``).

A training run renders guide views of the scenes of one or more experiment YAMLs (their terrain,
camera, light, BSDF and sensor, so the model sees the images the studies will see) on terrain
realisations the experiments do not use (another ``seed``), under several sun elevations, and
fits, by ``target``, the learned importance map (``map``, the default:
:func:`simlunar.planner.learning.train_learned_map`) or the residual model of the ``learned``
reconstruction (``reconstruction``: :func:`simlunar.planner.learning.train_learned_reconstruction`,
options of its features in the section ``reconstruction``). Presets listed in
``held_out_presets`` are never trained on (evaluate on them). Examples:
``experiments/training/learned_quarter.yaml``, ``experiments/training/learned_recon_quarter.yaml``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, field_validator, model_validator

from simlunar.config.derived import reconstruction_mapping, reconstruction_specs
from simlunar.config.fields import Deg, Density, _Model
from simlunar.config.loading import load_experiment
from simlunar.config.messages import validate_file_data
from simlunar.config.yamlio import load_yaml
from simlunar.errors import ConfigError
from simlunar.reconstruction import RECONSTRUCTIONS

__all__ = ["LearnedOptsCfg", "LearnedReconCfg", "TrainCfg", "load_training"]


class LearnedOptsCfg(_Model):
    """Options of :class:`simlunar.features.learned.LearnedOptions` (same defaults)."""

    layouts: int = Field(3, ge=1, le=100, description="uniform layouts averaged per target")
    pixels_per_example: int = Field(10_000, ge=100, description="training pixels per example")
    max_iter: int = Field(200, ge=1, le=10_000, description="boosting rounds")
    max_leaf_nodes: int = Field(31, ge=2, description="leaves per tree")
    min_samples_leaf: int = Field(50, ge=1, description="pixels per leaf (at least)")
    learning_rate: float = Field(0.1, gt=0, description="boosting learning rate")
    l2_regularization: float = Field(0.0, ge=0, description="leaf-value L2 penalty")
    threads: int = Field(
        1,
        ge=1,
        le=64,
        description="OpenMP threads of the boosting (1: fastest on a loaded machine)",
    )


class LearnedReconCfg(_Model):
    """Features of the learned reconstruction (``target: reconstruction`` only)."""

    with_shading: bool = Field(
        False,
        description="add the detail of the registered `shading` reconstruction as a feature "
        "(the model then runs it at every reconstruction)",
    )
    shading_options: dict[str, Any] = Field(
        default_factory=dict, description="options of the `shading` reconstruction"
    )

    @model_validator(mode="after")
    def _shading(self) -> LearnedReconCfg:
        if self.shading_options and not self.with_shading:
            raise ValueError("shading_options: only with with_shading: true")
        if self.with_shading:
            if "shading" not in RECONSTRUCTIONS:
                raise ValueError(
                    "with_shading: needs the reconstruction 'shading', which this simlunar "
                    f"does not register (have: {', '.join(RECONSTRUCTIONS)})"
                )
            RECONSTRUCTIONS["shading"].make_options(self.shading_options)
        return self


class TrainCfg(_Model):
    """A training run of the learned importance map or of the learned reconstruction."""

    name: str = Field(description="names the run (recorded with the model)")
    description: str = ""
    target: Literal["map", "reconstruction"] = Field(
        "map",
        description="what is learned: the importance map (features.learned) or the residual "
        "of the `learned` reconstruction (reconstruction.learned)",
    )
    seed: int = Field(
        ge=0,
        description="terrain and training seed; use one no experiment uses, so every terrain "
        "the model sees is held out from the studies",
    )
    experiments: list[str] = Field(
        min_length=1, description="experiment YAMLs whose scenes are rendered (relative paths: "
        "to this file)",
    )  # fmt: skip
    scale: float = Field(1.0, gt=0, le=1, description="terrain.scale of every scene")
    held_out_presets: list[str] = Field(
        default_factory=list, description="presets of the experiments never trained on"
    )
    terrain_seeds: int = Field(2, ge=1, le=100, description="realisations per preset")
    sun_elevations_deg: (
        list[Annotated[Deg, Field(gt=0, le=90, description="above the horizon (0 < e <= 90)")]]
        | None
    ) = Field(
        None,
        description="sun elevations rendered per terrain (each 0 < e <= 90: a sun at or below "
        "the horizon lights nothing); null = each experiment's own",
    )
    densities: list[Density] = Field(
        min_length=1,
        description="densities k / N trained: map, one model each; reconstruction, the "
        "layouts' densities of one model (density is a feature)",
    )
    options: LearnedOptsCfg = Field(default_factory=LearnedOptsCfg)
    reconstruction: LearnedReconCfg | None = Field(
        None, description="features of the learned reconstruction (target: reconstruction)"
    )
    error_reconstruction: str | dict[str, dict[str, Any]] = Field(
        "linear",
        description="target: map only: the reconstruction whose error the map learns, a name "
        "or {name: {options}} of the reconstruction registry: linear (the paper's) or e.g. "
        "shading (the fused model: sample where the camera cannot tell); a guided one reads "
        "each example's guide frames (render.guide_frames of its experiment)",
    )
    model: str = Field(description="output model file (.joblib, its .json beside it)")

    @field_validator("model")
    @classmethod
    def _joblib(cls, v: str) -> str:
        if not v.endswith(".joblib"):
            raise ValueError(f"a learned model file ends in .joblib, got {v!r}")
        return v

    @model_validator(mode="after")
    def _distinct(self) -> TrainCfg:
        if len(set(self.densities)) != len(self.densities):
            raise ValueError(f"densities: must be distinct, got {self.densities}")
        if self.reconstruction is not None and self.target != "reconstruction":
            raise ValueError("reconstruction: only with target: reconstruction")
        if self.error_reconstruction != "linear" and self.target != "map":
            raise ValueError("error_reconstruction: only with target: map")
        return self

    @field_validator("error_reconstruction")
    @classmethod
    def _one_registered_reconstruction(cls, v):
        if isinstance(v, dict) and len(v) == 1 and "reconstruction" in next(iter(v.values())):
            raise ValueError("a registered reconstruction's name, not a label")
        (item,) = reconstruction_specs([v])  # names and options checked by the registry
        return item

    def error_reconstruction_spec(self) -> tuple[str, dict]:
        """``(name, options)`` of ``error_reconstruction``."""
        ((name, opts),) = reconstruction_mapping([self.error_reconstruction]).items()
        return name, opts

    def recorded(self) -> dict:
        """The config as recorded with the model: without ``error_reconstruction`` when it is
        linear, so a map trained as before has the record of before."""
        out = self.model_dump(mode="json")
        if out.get("error_reconstruction") == "linear":
            del out["error_reconstruction"]
        return out


def load_training(path: str | Path):
    """The training config and its experiments, ``(TrainCfg, list of ExperimentCfg)``, of a
    training YAML (a one-line ``ConfigError`` for each problem)."""
    path = Path(path)
    data = load_yaml(path)
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: <root>: expected a mapping of keys")
    cfg = validate_file_data(TrainCfg, data, path)
    experiments = []
    for i, name in enumerate(cfg.experiments):
        p = Path(name) if Path(name).is_absolute() else path.parent / name
        if not p.is_file():
            raise ConfigError(f"{path}: experiments[{i}]: file not found: {p}")
        exp = load_experiment(p)
        if exp.study.kind != "sampling":
            raise ConfigError(f"{path}: experiments[{i}]: {p} is not a sampling experiment")
        experiments.append(exp)
    presets = {_preset(e, v) for e in experiments for v in _sweep_presets(e)}
    for i, name in enumerate(cfg.held_out_presets):
        if name not in presets:
            raise ConfigError(
                f"{path}: held_out_presets[{i}]: {name!r} is in none of the experiments "
                f"(have: {', '.join(sorted(presets))})"
            )
    if not presets - set(cfg.held_out_presets):
        raise ConfigError(f"{path}: held_out_presets: leaves no preset to train on")
    return cfg, experiments


def _sweep_presets(exp) -> list:
    return list(exp.sweep.get("terrain.preset") or [exp.terrain.preset])


def _preset(exp, value) -> str:
    return str(value if value is not None else exp.terrain.preset)
