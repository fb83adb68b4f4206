"""report.html of a result folder: what ran, the tables, the figures embedded, the timings."""

from __future__ import annotations

import base64
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from browser import dump_dom, images_load
from fake_unit import fake_unit

from simlunar.config.schema import ExperimentCfg
from simlunar.errors import ResultFolderError
from simlunar.pipeline.runner import run_experiment
from simlunar.results.md_tables import parse_markdown
from simlunar.results.report import (
    build_report,
    config_differences,
    read_captions,
    run_overrides,
    write_report,
)

ROOT = Path(__file__).resolve().parents[2]
FAKE_CLI = ROOT / "tests" / "pipeline" / "fake_cli.py"


def _cfg() -> ExperimentCfg:
    return ExperimentCfg.model_validate(
        {
            "name": "report_test",
            "description": "a <small> study & its report",
            "seed": 5,
            "terrain": {"preset": "aerial_1", "scale": 0.125},
            "study": {
                "strategies": ["random", "grid", "wavelet"],
                "densities": [0.5, 0.25, 0.125],
                "trials": 2,
                "metrics": ["mse"],
            },
            "figures": {"sparse_mesh_density": None, "formats": ["png"]},
        }
    )


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("report") / "o"
    run_experiment(_cfg(), out, compute=fake_unit, progress=False)
    return out


def test_read_captions(tmp_path):
    (tmp_path / "captions.md").write_text(
        "# Figure captions\n\n## a\n\nFirst line\nsecond line.\n\n## b\n\nB.\n"
    )
    assert read_captions(tmp_path) == {"a": "First line second line.", "b": "B."}
    assert read_captions(tmp_path / "none") == {}


def test_config_differences():
    base = {"a": {"b": 1, "c": [1, 2]}, "d": "x"}
    other = {"a": {"b": 1, "c": [1, 3], "e": 0}, "d": "x"}
    assert config_differences(base, other) == {"a.c": [1, 3], "a.e": 0}
    assert config_differences(base, base) == {}


def test_run_overrides_of_a_shipped_file(tmp_path):
    # the folder's config is the shipped quickstart with two keys changed
    from simlunar.config.loading import load_experiment, to_plain
    from simlunar.config.yamlio import dump_yaml

    shipped = ROOT / "experiments" / "quickstart.yaml"
    cfg = load_experiment(shipped, {"render.spp": 3, "study.trials": 1})
    (tmp_path / "config.yaml").write_text(dump_yaml(to_plain(cfg)))
    assert run_overrides(tmp_path, shipped) == {"render.spp": 3, "study.trials": 1}
    assert run_overrides(tmp_path, tmp_path / "missing.yaml") == {}


def test_report_holds_tables_figures_provenance_and_timings(folder):
    text = build_report(folder)
    # every table of scores.md, cell for cell
    tables = [b for b in parse_markdown((folder / "scores.md").read_text()) if b.kind == "table"]
    assert text.count('<table class="scores">') == len(tables) >= 2
    assert "<td>Wavelet</td>" in text or ">Wavelet<" in text
    # every PNG of figures/ embedded byte for byte, with its caption
    pngs = sorted((folder / "figures").glob("*.png"))
    assert pngs
    embedded = re.findall(r'src="data:image/png;base64,([^"]+)"', text)
    assert sorted(base64.b64decode(e) for e in embedded) == sorted(p.read_bytes() for p in pngs)
    captions = read_captions(folder / "figures")
    assert captions
    for stem in captions:
        assert f'id="fig-{stem}"' in text
    # what ran: provenance's commit, versions, hashes; the description escaped
    prov = json.loads((folder / "provenance.json").read_text())
    assert prov["git"]["commit"][:12] in text
    assert f"<td>numpy</td><td>{prov['versions']['numpy']}</td>" in text
    assert prov["files"]["results.csv"] in text
    assert "a &lt;small&gt; study &amp; its report" in text and "<small>" not in text
    assert f"{prov['timings']['run_s']:.1f}" in text
    # self-contained: no file or network reference
    assert not re.search(r'(src|href)="(?!data:|#)', text)


def test_report_of_a_folder_without_provenance(tmp_path):
    with pytest.raises(ResultFolderError, match=r"no readable provenance\.json"):
        build_report(tmp_path)


def _cli(*args, cwd):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    return subprocess.run(
        [sys.executable, str(FAKE_CLI), *args], cwd=cwd, env=env, capture_output=True, text=True
    )


def test_run_writes_the_report_and_report_rewrites_it(tmp_path):
    exp = tmp_path / "exp.yaml"
    exp.write_text(
        "name: cli_report\nterrain: {preset: aerial_1, scale: 0.125}\n"
        "study: {strategies: [random, grid], densities: [0.5, 0.25], trials: 2, metrics: [mse]}\n"
    )
    r = _cli("run", str(exp), "--out", "o", "--no-progress", "--no-figures", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    report = tmp_path / "o" / "report.html"
    assert f"report: {Path('o') / 'report.html'}" in r.stdout and report.is_file()
    report.unlink()
    r = _cli("report", "o", cwd=tmp_path)
    assert r.returncode == 0 and report.is_file()
    assert "No figures" in report.read_text()
    r = _cli("report", "nowhere", cwd=tmp_path)
    assert r.returncode == 2 and "nowhere: no such folder" in r.stderr


@pytest.mark.slow
def test_report_opens_in_chromium_with_its_tables_and_images(folder, tmp_path):
    path = write_report(folder)
    dom = dump_dom(path.as_uri(), tmp_path / "profile")
    tables = [b for b in parse_markdown((folder / "scores.md").read_text()) if b.kind == "table"]
    assert dom.count('<table class="scores">') == len(tables)
    for heading in (b.text for b in parse_markdown((folder / "scores.md").read_text())):
        if heading.startswith("report_test:"):
            assert heading.replace("&", "&amp;") in dom
    srcs = re.findall(r'<img [^>]*src="(data:image/png;base64,[^"]+)"', dom)
    n_png = len(list((folder / "figures").glob("*.png")))
    assert len(srcs) == n_png > 0
    loaded, total, line = images_load(srcs, folder, tmp_path / "probe")
    assert (loaded, total) == (n_png, n_png), line
