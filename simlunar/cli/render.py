"""``simlunar render``: one scene YAML rendered into a folder."""

from __future__ import annotations

from pathlib import Path

import typer

from simlunar.cli.common import echo, user_input

__all__ = ["render"]

# The library is imported inside each command, not at the top: importing it takes about 3 s (the
# scientific stack, and config.registry, which reads every planner, sensor and renderer), which
# `simlunar render --help` and a mistyped option should not pay (0.3 s with these imports here).


def render(
    scene: str = typer.Argument(..., help="scene YAML (e.g. scenes/quickstart_scene.yaml)"),
    out: str = typer.Option(None, "--out", help="output folder [default: results/render/<name>]"),
) -> None:
    """Render a scene: radiance.exr (linear), preview.png, ground_truth.exr/.npz, scene.json."""
    from simlunar.config.scene import load_scene
    from simlunar.pipeline.preflight import (
        check_camera,
        check_out_dir,
        check_renderer,
        terrain_facts,
    )
    from simlunar.pipeline.scene import check_render_folder, render_scene

    with user_input():
        cfg = load_scene(scene)
    out_dir = Path(out) if out else Path("results") / "render" / cfg.name
    check_out_dir(out_dir)
    check_render_folder(out_dir)
    check_renderer()
    # the DEM's contents and the view, before rendering
    check_camera(cfg.render, terrain_facts(cfg.terrain))
    paths = render_scene(cfg, out_dir)
    for name, path in paths.items():
        echo(f"{name:<17} {path}")
    echo(f"rendered {cfg.name} into {out_dir}")
