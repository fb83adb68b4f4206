"""Exports never overwrite or delete silently: labels that make one file name get files of
their own, a manifest never names a file twice, and asking a finished folder for an export
with --no-figures keeps its figures (and the report's images)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.results import array_exports as ax
from simlunar.results.folder import prune_figures
from simlunar.results.report import write_report
from tests.results.test_array_exports import _payload

ROOT = Path(__file__).resolve().parents[2]
QUICKSTART = str(ROOT / "experiments" / "quickstart.yaml")
TINY = ["--set", "study.strategies=[random]", "--set", "study.trials=1",
        "--set", "study.densities=[1/16]", "--set", "terrain.scale=0.05"]  # fmt: skip


def test_labels_that_make_one_file_name_get_a_file_each(tmp_path):
    # "a b", "a-b" and "a/b" all become "a-b" in a file name: before, the later export
    # overwrote the earlier one and the manifest named one file three times
    t, depth, recon, _ = _payload()
    from simlunar.geometry import OrthoCamera

    cam = OrthoCamera.nadir_for_grid(t.shape, t.spacing, t.origin, altitude=50.0)
    grids = {("p", 0, "a b"): recon, ("p", 0, "a-b"): depth + 0.5, ("p", 0, "a/b"): depth - 0.5}
    payload = ax.array_export_payload(
        grids, depth, densities=[1 / 4], ks=[12], view=ax.export_view(cam, t)
    )
    folder = ax.write_array_export(tmp_path / "u", payload)
    manifest = json.loads((folder / "manifest.json").read_text())
    names = [f[k] for f in manifest["files"] for k in ("tif", "exr")]
    assert len(names) == len(set(names)) == 2 * (1 + 2 * 3)
    # each label's own grid is in the file its manifest entry names
    want = {"a b": 50.0 - recon, "a-b": 50.0 - (depth + 0.5), "a/b": 50.0 - (depth - 0.5)}
    for f in manifest["files"]:
        if f["channel"] == "height" and "reconstruction" in f:
            got, _, _, _ = ax.read_geotiff(folder / f["tif"])
            np.testing.assert_allclose(got, want[f["reconstruction"]], atol=1e-4)
    assert {f["tif"] for f in manifest["files"] if f["channel"] == "height"} >= {
        "p_1-4_a-b_height.tif",
        "p_1-4_a-b+2_height.tif",
        "p_1-4_a-b+3_height.tif",
    }


def test_prune_figures_takes_the_captions_of_removed_figures(tmp_path):
    # captions.md left behind described figures the report no longer shows
    fig = tmp_path / "figures"
    fig.mkdir()
    for name in ("a.png", "captions.md"):
        (fig / name).write_text("x")
    prune_figures(tmp_path, keep=[fig / "a.png", fig / "captions.md"])
    assert sorted(p.name for p in fig.iterdir()) == ["a.png", "captions.md"]
    prune_figures(tmp_path, keep=())
    assert list(fig.iterdir()) == []


def _run(out, *extra):
    r = CliRunner().invoke(app, ["run", QUICKSTART, "--out", str(out), "--no-progress", *TINY, *extra])  # fmt: skip
    assert r.exit_code == 0, r.output
    return r


def test_save_arrays_with_no_figures_on_a_finished_folder_keeps_its_figures(tmp_path):
    out = tmp_path / "q"
    _run(out)
    figures = {p.name: p.read_bytes() for p in (out / "figures").iterdir()}
    assert any(n.endswith(".png") for n in figures) and "captions.md" in figures
    results = (out / "results.csv").read_bytes()
    r = _run(out, "--save-arrays", "--no-figures")
    assert "1 computed" in r.output  # computed again for its export alone
    assert (out / "arrays" / "unit0" / "manifest.json").is_file()
    # before, every figure was deleted without a word and the report had no images
    assert {p.name: p.read_bytes() for p in (out / "figures").iterdir()} == figures
    assert (out / "results.csv").read_bytes() == results
    html = write_report(out).read_text()
    assert html.count("<img") == sum(n.endswith(".png") for n in figures)
    # and a rerun of the finished folder computes nothing
    assert "0 computed" in _run(out, "--save-arrays", "--no-figures").output
