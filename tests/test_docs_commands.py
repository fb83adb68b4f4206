"""Every command shown in README.md and docs/*.md runs (or is marked as a long run there).

The code blocks are read at test time, so whatever the docs say now is what is tested:

* ``bash`` blocks: each line is a command, run in order in one scratch folder holding the
  repository's ``scenes/`` and a shrunk copy of ``experiments/`` (:func:`_shrink`: a small
  scene, 2 samples per pixel, few trials and densities, the first two points of each sweep
  axis), so ``results/``, ``build/`` and written files land there and the commands' own
  options still apply. ``simlunar`` / ``.venv/bin/simlunar`` run this checkout's CLI;
  ``make TARGET`` is dry-run (``make -n``), since the targets build a virtual environment. A
  line whose comment says ``long run`` (``# long run``, ``# a cluster; long run``) is only checked: the subcommand's ``--help`` works
  and the files it names exist.
* ``python`` blocks run in a subprocess in such a folder. A block marked ``runnable`` in its
  fence (```` ```python runnable ````) is self-contained: it runs exactly as written, nothing
  prepended, so a reader can paste it. Other blocks continue an earlier context (``terrain``,
  ``depth``, ...) and get a small one from :data:`PRELUDES`. A block whose first line is
  ``# long run`` is only compiled.
* ``yaml`` blocks must parse.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```(\w*)([^\n]*)\n(.*?)^```", re.S | re.M)
RUNNABLE = "runnable"
LONG = "# long run"
TIMEOUT_S = 600

PRELUDES = {
    "sampling-study.md": """
import numpy as np
from scipy.ndimage import gaussian_filter
depth = gaussian_filter(np.random.default_rng(0).normal(size=(128, 128)), 4.0)
image = 0.5 + 10.0 * np.gradient(depth)[1]
""",
}


def _geotiff_prelude(text: str) -> str:
    """Small GeoTIFFs for every ``load_dem("X.tif", ...)`` of a block: georeferenced (transform
    and a projected CRS in metres) unless the call gives ``spacing=``, which is for plain files."""
    lines = [
        "import numpy as np",
        "import rasterio",
        "from rasterio.transform import from_origin",
    ]
    for name, args in re.findall(r'load_dem\("([^"]+\.tiff?)"([^)]*)\)', text):
        geo = "" if "spacing" in args else ", transform=from_origin(0, 30, 5, 5), crs='EPSG:32633'"
        lines += [
            f"with rasterio.open({name!r}, 'w', driver='GTiff', width=8, height=6, count=1,",
            f"                   dtype='float32', nodata=-9999{geo}) as f:",
            "    f.write(np.arange(48, dtype=np.float32).reshape(6, 8), 1)",
        ]
    return "\n".join(lines) + "\n"


def _blocks():
    out = []
    for doc in DOCS:
        text = doc.read_text()
        for i, m in enumerate(FENCE.finditer(text)):
            lang = m.group(1).lower()
            runnable = RUNNABLE in m.group(2).split()
            line = text.count("\n", 0, m.start()) + 1
            out.append(
                pytest.param(
                    doc,
                    lang,
                    m.group(3),
                    runnable,
                    id=f"{doc.name}:{line}:{lang or i}{'-runnable' if runnable else ''}",
                )
            )
    return out


BLOCKS = _blocks()


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env.setdefault("MPLBACKEND", "Agg")
    env.setdefault("DRJIT_CACHE_DIR", str(ROOT / "build" / "drjit-cache"))
    return env


def _shrink(cfg: dict) -> dict:
    """A small, fast version of an experiment (same keys, same study kind)."""
    cfg.setdefault("terrain", {})["scale"] = 0.0625
    cfg.setdefault("render", {})["spp"] = 2
    study = cfg.setdefault("study", {})
    study["trials"] = 1
    if study.get("kind", "sampling") == "sampling":
        study["trials"] = 2
        # the same two densities, written as the file wrote them (a --set of one key of a
        # {from, to, count} mapping must still find a mapping)
        mapping = isinstance(study.get("densities"), dict)
        study["densities"] = (
            {"from": "1/4", "to": "1/16", "count": 2} if mapping else ["1/4", "1/16"]
        )
    else:
        cfg["terrain"]["scale"] = 0.1
        study["projector_px"], study["camera_px"] = [32, 24], [64, 48]
    cfg["figures"] = {**(cfg.get("figures") or {}), "formats": ["png"]}
    for key, values in (cfg.get("sweep") or {}).items():
        cfg["sweep"][key] = values[:2]
    return cfg


def _scratch(tmp_path: Path) -> Path:
    (tmp_path / "scenes").symlink_to(ROOT / "scenes")
    (tmp_path / "experiments").mkdir()
    for f in (ROOT / "experiments").glob("*.yaml"):
        cfg = _shrink(yaml.safe_load(f.read_text()))
        (tmp_path / "experiments" / f.name).write_text(yaml.safe_dump(cfg, sort_keys=False))
    return tmp_path


def _commands(text: str) -> list[str]:
    lines, cur = [], ""
    for raw in text.splitlines():
        if raw.rstrip().endswith("\\"):
            cur += raw.rstrip()[:-1] + " "
            continue
        cur += raw
        if cur.strip() and not cur.strip().startswith("#"):
            lines.append(cur.strip())
        cur = ""
    return lines


def _run(argv, cwd, what):
    r = subprocess.run(argv, cwd=cwd, env=_env(), capture_output=True, text=True, timeout=TIMEOUT_S)
    assert r.returncode == 0, (
        f"{what}\n(exit {r.returncode})\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"
    )
    return r


def _cli_argv(args: list[str]) -> list[str]:
    argv = [sys.executable, "-m", "simlunar.cli", *args]
    return [*argv, "--no-progress"] if args and args[0] == "run" else argv


def _check_long(args: list[str], line: str, cwd: Path) -> None:
    for a in args:
        if a.endswith((".yaml", ".yml")) and not a.startswith("--"):
            assert (ROOT / a).is_file(), f"{line}: {a} does not exist"
    if args[0] in ("simlunar", ".venv/bin/simlunar"):
        sub = [a for a in args[1:2] if not a.startswith("-")]
        _run([sys.executable, "-m", "simlunar.cli", *sub, "--help"], cwd, line)
    elif args[0] in ("python", "python3", ".venv/bin/python") and args[1:2] == ["-m"]:
        _run([sys.executable, "-m", args[2], "--help"], cwd, line)


@pytest.mark.parametrize(("doc", "lang", "text", "runnable"), BLOCKS)
def test_doc_block_runs(doc, lang, text, runnable, tmp_path):
    cwd = _scratch(tmp_path)
    if lang in ("bash", "sh", "shell", "console"):
        for line in _commands(text):
            long_run = "#" in line and LONG[2:] in line.split("#", 1)[1]
            args = shlex.split(line, comments=True)
            if long_run:
                _check_long(args, line, cwd)
            elif args[0] in ("simlunar", ".venv/bin/simlunar"):
                _run(_cli_argv(args[1:]), cwd, line)
            elif args[0] == "make":
                _run(["make", "-n", "-C", str(ROOT), *args[1:]], cwd, line)
            elif args[0] in ("python", "python3", ".venv/bin/python"):
                _run([sys.executable, *args[1:]], cwd, line)
            else:
                pytest.fail(f"{doc.name}: no runner for {line!r}; run it here or mark {LONG!r}")
    elif lang == "python":
        first = text.lstrip().splitlines()[0] if text.strip() else ""
        if first.startswith("#") and LONG[2:] in first:
            compile(text, str(doc), "exec")
            return
        if runnable:  # as a reader pastes it: nothing prepended
            (cwd / "block.py").write_text(text)
            _run([sys.executable, "block.py"], cwd, f"{doc.name} runnable python block:\n{text}")
            return
        script = PRELUDES.get(doc.name, "") + _geotiff_prelude(text) + "\n" + text
        (cwd / "block.py").write_text(script)
        _run([sys.executable, "block.py"], cwd, f"{doc.name} python block:\n{text}")
    elif lang in ("yaml", "yml"):
        yaml.safe_load(text)


def test_blocks_are_found():
    # the docs show commands and code; an empty parametrisation would pass silently
    langs = {p.values[1] for p in BLOCKS}
    assert {"bash", "python"} <= langs
    assert any(p.values[0].name == "README.md" for p in BLOCKS)


def test_runnable_blocks_are_marked_where_a_reader_starts():
    # the README's example and rendering.md's "From Python" are self-contained and marked so;
    # a runnable block names everything it uses (a prelude would hide a missing import)
    marked = {(p.values[0].name, p.values[1]) for p in BLOCKS if p.values[3]}
    assert {("README.md", "python"), ("rendering.md", "python")} <= marked
    assert all(p.values[1] == "python" for p in BLOCKS if p.values[3])
    assert "rendering.md" not in PRELUDES


def test_long_run_marker_is_only_a_check(tmp_path):
    # a marked line is not executed: a missing experiment file fails the check itself
    with pytest.raises(AssertionError, match="does not exist"):
        _check_long(["simlunar", "run", "experiments/nope.yaml"], "x", _scratch(tmp_path))
