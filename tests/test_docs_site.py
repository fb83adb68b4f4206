"""The documentation site (``make docs``): its generated pages, and the built site opened in
headless Chromium (pages render, the gallery's images load, search finds a term)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from browser import dump_dom, images_load

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

import simlunar_docs  # noqa: E402

HTML = ROOT / "build" / "docs" / "html"


def test_experiment_table_lists_every_shipped_experiment():
    text = simlunar_docs._experiment_table(simlunar_docs._experiments())
    rows = [ln for ln in text.splitlines() if ln.startswith("| `")]
    names = sorted(p.stem for p in (ROOT / "experiments").glob("*.yaml"))
    assert [re.match(r"\| `([^`]+)`", r).group(1) for r in rows] == names
    assert "| `quickstart` | sampling | 1/8-scale aerial scene 1" in text


def test_bars_escaped_in_prose_only():
    lines = [
        "weights |grad truth| and ``|x|`` and :math:`|H|`",
        "| a | b |",
        "Example::",
        "",
        "    x = |y|",
        "back |z|",
        "|H| >= 0",
    ]
    simlunar_docs._escape_bars(lines)
    assert lines == [
        r"weights \|grad truth\| and ``|x|`` and :math:`|H|`",
        "| a | b |",
        "Example::",
        "",
        "    x = |y|",
        r"back \|z\|",
        r"\|H\| >= 0",
    ]


def test_an_options_class_gets_its_fields_documented_from_their_declarations():
    from simlunar.reconstruction.calibration import CalibrationOptions

    lines = ["Options of the calibration."]
    simlunar_docs._on_docstring(None, "class", "x", CalibrationOptions, {}, lines)
    assert lines[1:4] == ["", "Attributes", "----------"]
    assert "shadow : float, default 0.02" in lines
    # a docstring that writes its own section keeps it, and only it
    own = ["Summary.", "", "Attributes", "----------", "shadow : float", "    Mine."]
    simlunar_docs._on_docstring(None, "class", "x", CalibrationOptions, {}, own)
    assert own[-1] == "    Mine." and own.count("Attributes") == 1
    # a function's docstring is left alone
    fn = ["Summary."]
    simlunar_docs._on_docstring(None, "function", "x", CalibrationOptions, {}, fn)
    assert fn == ["Summary."]


def test_api_pages_cover_every_module(tmp_path):
    text = simlunar_docs._api(tmp_path)
    pages = {p.stem for p in (tmp_path / "api").glob("*.rst")}
    assert "simlunar.results.report" in pages
    assert "simlunar.cli.__main__" not in pages  # importing it would run the CLI
    for page in pages:
        assert f"api/{page}" in text


def test_gallery_names_folder_overrides_and_unrun(tmp_path, monkeypatch):
    # a result folder of quickstart with one figure and its caption; every other experiment
    # is listed as not run
    folder = tmp_path / "results" / "quickstart"
    (folder / "figures").mkdir(parents=True)
    (folder / "figures" / "captions.md").write_text("# Figure captions\n\n## a\n\nCaption A.\n")
    (folder / "figures" / "a.png").write_bytes(b"\x89PNG\r\n")
    monkeypatch.setattr(simlunar_docs, "ROOT", tmp_path)
    monkeypatch.setattr(simlunar_docs, "run_overrides", lambda f: {"render.spp": 2})
    exps = [("quickstart", {"description": "d"}), ("other", {})]
    text = simlunar_docs._gallery(exps, tmp_path / "gen")
    assert "Result folder `results/quickstart`" in text
    assert "`render.spp=2`" in text
    assert "```{figure} gallery/quickstart/a.png" in text and "Caption A." in text
    assert (tmp_path / "gen" / "gallery" / "quickstart" / "a.png").is_file()
    assert text.rstrip().endswith("- `other`")


@pytest.fixture(scope="session")
def site() -> Path:
    """The site built as `make docs` builds it, into build/docs/html, but from a fresh environment
    (-E): an incremental build re-reads only changed pages, so a warning on an unchanged page
    would pass here and fail on a fresh clone."""
    pytest.importorskip("sphinx", reason="the docs extra is not installed: pip install -e .[docs]")
    simlunar_docs.gallery_run(ROOT)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    argv = [sys.executable, "-m", "sphinx", "-b", "html", "-E", "-W", "--keep-going", "-q"]
    r = subprocess.run(
        [*argv, "docs", str(HTML)], cwd=ROOT, env=env, capture_output=True, text=True, check=False
    )
    assert r.returncode == 0, f"sphinx-build failed:\n{r.stdout[-3000:]}\n{r.stderr[-5000:]}"
    return HTML


@pytest.mark.slow
def test_pages_render_in_chromium(site, tmp_path):
    dom = dump_dom((site / "index.html").as_uri(), tmp_path / "profile")
    assert "<h1>simlunar" in dom
    for page in ("install.html", "experiments.html", "_generated/gallery.html"):
        assert f'href="{page}' in dom, page
    api = dump_dom((site / "_generated/api/simlunar.results.report.html").as_uri(), tmp_path / "p2")
    # autodoc rendered the numpydoc docstring: the function, its Raises section
    assert 'id="simlunar.results.report.build_report"' in api
    assert "ResultFolderError" in api


@pytest.mark.slow
def test_gallery_images_load_in_chromium(site, tmp_path):
    page = site / "_generated" / "gallery.html"
    dom = dump_dom(page.as_uri(), tmp_path / "profile")
    srcs = re.findall(r'<img [^>]*src="([^"]+)"', dom)
    figures = dom.count("<figure")
    assert figures >= 5, f"only {figures} figures in the gallery"
    assert len(srcs) >= figures
    loaded, total, line = images_load(srcs, page.parent, tmp_path / "probe")
    assert (loaded, total) == (len(srcs), len(srcs)), line
    assert "figure-caption" in dom or "<figcaption" in dom


@pytest.mark.slow
def test_search_finds_a_term_in_chromium(site, tmp_path):
    url = (site / "search.html").as_uri()
    dom = dump_dom(f"{url}?q=headroom", tmp_path / "p1", budget_ms=8000)
    hits = re.findall(r'<li[^>]*>\s*<a [^>]*href="([^"]+)"', dom.split('id="search-results"')[-1])
    assert hits, f"search for 'headroom' found nothing:\n{dom[-3000:]}"
    # a word in no page finds nothing: the check above can fail
    none = dump_dom(f"{url}?q=zyxwvutsrqp", tmp_path / "p2", budget_ms=8000)
    rest = none.split('id="search-results"')[-1]
    assert not re.findall(r'<li[^>]*>\s*<a [^>]*href="', rest)


def test_the_index_links_every_guide_and_the_reproduction():
    index = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    toctree = index.split("```{toctree}", 1)[1].split("```", 1)[0].split()
    guides = sorted(p.stem for p in (ROOT / "docs").glob("*.md") if p.stem != "index")
    assert "reproduction" in guides
    missing = [g for g in guides if g not in toctree or f"]({g}.md)" not in index]
    assert not missing, f"guides not in the index's toctree and prose: {missing}"
    # the site's reproduction page is the repository's REPRODUCTION.md itself, not a copy
    page = (ROOT / "docs" / "reproduction.md").read_text(encoding="utf-8")
    assert "{include} ../REPRODUCTION.md" in page and len(page.splitlines()) <= 3


@pytest.mark.slow
def test_reproduction_and_a_reconstruction_figure_in_chromium(site, tmp_path):
    dom = dump_dom((site / "index.html").as_uri(), tmp_path / "p0")
    assert 'href="reproduction.html' in dom
    rep = dump_dom((site / "reproduction.html").as_uri(), tmp_path / "p1")
    assert "Reproducing the paper" in rep and "Table 2: moonyard" in rep
    assert rep.count("<table") >= 10  # its tables rendered as tables, not as text
    page = site / "reconstruction.html"
    dom = dump_dom(page.as_uri(), tmp_path / "p2")
    srcs = [s for s in re.findall(r'<img [^>]*src="([^"]+)"', dom) if "recon_panels" in s]
    assert srcs, "the reconstruction guide shows no reconstruction panels"
    loaded, total, line = images_load(srcs, page.parent, tmp_path / "probe")
    assert (loaded, total) == (len(srcs), len(srcs)), line
