"""The notebooks in notebooks/ run on a quickstart-sized result folder (outputs stripped in git)."""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest
from typer.testing import CliRunner

from simlunar.cli import app

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """A shrunken quickstart with a two-point sun-elevation sweep (covers the ablation notebook)."""
    out = tmp_path_factory.mktemp("nb") / "quickstart"
    r = CliRunner().invoke(
        app,
        [
            "run",
            str(ROOT / "experiments" / "quickstart.yaml"),
            "--out",
            str(out),
            "--no-progress",
            "--no-figures",
            "--set",
            "terrain.scale=0.0625",
            "--set",
            "render.spp=4",
            "--set",
            "study.strategies=[random, wavelet]",
            "--set",
            "study.densities=[1/4, 1/32]",
            "--set",
            "study.trials=2",
            "--set",
            "study.metrics=[mse]",
            "--set",
            "sweep={render.light.elevation_deg: [20, 60]}",
        ],
    )
    assert r.exit_code == 0, r.output
    return out


def test_notebooks_exist_and_are_stripped():
    assert {p.stem for p in NOTEBOOKS} >= {
        "fig3_error_vs_density",
        "fig_image_panels",
        "fig4_sparse_mesh",
        "ablation_scores",
        "fused_camera",
    }
    for p in NOTEBOOKS:
        nb = nbformat.read(p, as_version=4)
        for cell in nb.cells:
            if cell.cell_type == "code":
                assert cell.outputs == [] and cell.execution_count is None, p.name


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path, results, monkeypatch):
    from nbclient import NotebookClient

    monkeypatch.setenv("SIMLUNAR_RESULTS", str(results))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(path, as_version=4)
    NotebookClient(
        nb, timeout=120, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}}
    ).execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    text = "".join(o.get("text", "") for o in outputs if o.output_type == "stream")
    assert "quickstart - 2 unit(s)" in text
    if path.stem in (
        "fig3_error_vs_density",
        "fig_image_panels",
        "fig4_sparse_mesh",
        "ablation_scores",
        "fused_camera",
    ):
        assert any("image/png" in o.get("data", {}) for o in outputs), path.name
    if path.stem == "fused_camera":
        # the quickstart reconstructs every plan twice: the notebook draws both, compares
        # shading with linear on each layout, and shows one plan reconstructed both ways
        assert "reconstructions: linear, shading" in text
        assert "Shading on Wavelet:" in text and "Shading on Random:" in text
        assert sum("image/png" in o.get("data", {}) for o in outputs) == 3
        assert "no reconstruction panels" not in text
