"""``simlunar schema``: the JSON Schema (or the Markdown reference) of the YAML documents."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from simlunar.cli.common import echo, flag
from simlunar.errors import ConfigError

__all__ = ["schema"]

# The library is imported inside each command, not at the top: importing it takes about 3 s (the
# scientific stack, and config.registry, which reads every planner, sensor and renderer), which
# `simlunar schema --help` and a mistyped option should not pay (0.3 s with these imports here).


def schema(
    out: str = typer.Option(None, "--out", help="write to this file instead of stdout"),
    kind: str = typer.Option(
        "experiment", "--kind", help="document kind: experiment, scene or preset"
    ),
    markdown: bool = flag("--markdown", "the YAML reference as Markdown (docs/experiments.md)"),
) -> None:
    """JSON Schema of experiment (scene, preset) YAMLs (for editors: yaml-language-server)."""
    from simlunar.config.docs import SCHEMA_KINDS, json_schema, reference_markdown
    from simlunar.pipeline.preflight import check_out_file
    from simlunar.results.store import atomic_write_text

    if kind not in SCHEMA_KINDS:
        raise ConfigError(
            f"--kind {kind}: unknown document kind (valid: {', '.join(SCHEMA_KINDS)})"
        )
    text = reference_markdown() if markdown else json.dumps(json_schema(kind), indent=2)
    if out:
        check_out_file(out)
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(out, text + "\n")
    else:
        echo(text)
