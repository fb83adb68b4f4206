"""``simlunar train``: the learned importance map from a training YAML."""

from __future__ import annotations

import shlex

import typer

from simlunar.cli.common import user_input
from simlunar.config.training import load_training
from simlunar.errors import SimlunarError
from simlunar.pipeline.train import train_from_config


def train(
    config: str = typer.Argument(
        ..., help="training YAML (e.g. experiments/training/learned_quarter.yaml)"
    ),
    out: str = typer.Option(None, "--out", help="model file (.joblib) [default: the YAML's model]"),
) -> None:
    """Train the learned importance map: <model>.joblib and its record <model>.json."""
    with user_input():
        cfg, experiments = load_training(config)
    if out is not None and not out.endswith(".joblib"):
        raise SimlunarError(f"--out {out}: a learned model file ends in .joblib")
    command = shlex.join(["simlunar", "train", config, *(["--out", out] if out else [])])
    model, record = train_from_config(cfg, experiments, out=out, command=command, log=typer.echo)
    typer.echo(f"model:  {model}")
    typer.echo(f"record: {record}")
