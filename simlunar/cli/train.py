"""``simlunar train``: the learned importance map or learned reconstruction from a training
YAML."""

from __future__ import annotations

import shlex

import typer

from simlunar.cli.common import echo, user_input
from simlunar.errors import SimlunarError

__all__ = ["train"]

# The library is imported inside each command, not at the top: importing it takes about 3 s (the
# scientific stack, and config.registry, which reads every planner, sensor and renderer), which
# `simlunar train --help` and a mistyped option should not pay (0.3 s with these imports here).


def train(
    config: str = typer.Argument(
        ..., help="training YAML (e.g. experiments/training/learned_quarter.yaml)"
    ),
    out: str = typer.Option(None, "--out", help="model file (.joblib) [default: the YAML's model]"),
) -> None:
    """Train a learned map or reconstruction: <model>.joblib and its record <model>.json."""
    from simlunar.config.training import load_training
    from simlunar.pipeline.train import train_from_config

    with user_input():
        cfg, experiments = load_training(config)
    if out is not None and not out.endswith(".joblib"):
        raise SimlunarError(f"--out {out}: a learned model file ends in .joblib")
    command = shlex.join(["simlunar", "train", config, *(["--out", out] if out else [])])
    model, record = train_from_config(cfg, experiments, out=out, command=command, log=echo)
    echo(f"model:  {model}")
    echo(f"record: {record}")
