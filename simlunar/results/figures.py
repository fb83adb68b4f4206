"""Write a result folder's ``figures/`` from its ``results.csv`` and cached unit arrays.

Used by ``simlunar run`` at the end of a run and by ``simlunar figures RESULTS_DIR`` (which
redraws without recomputing anything).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

from simlunar.errors import ResultFolderError
from simlunar.results.folder import prune_figures, read_folder_config
from simlunar.results.store import UnitCache, atomic_write_bytes, file_sha256, read_csv

__all__ = [
    "DRAWING_MODULES",
    "NOT_DRAWN",
    "STAMP",
    "figure_inputs",
    "load_results",
    "load_unit_arrays",
    "write_captions",
    "write_figures",
    "write_figures_pruned",
]


def load_results(out_dir: str | Path) -> dict:
    """Everything a figure needs from a result folder.

    Returns
    -------
    dict
        ``config`` (dict), ``rows`` (list of dict, strings as in the CSV), ``units`` (list of
        unit records in results order: sweep, scores, config, key) and ``dir`` (Path).

    Raises
    ------
    ResultFolderError
        ``out_dir`` is not a finished result folder, or its files disagree with each other
        (``provenance.json`` records the SHA-256 of ``config.yaml``, ``results.csv`` and the
        tables it was written with) or cannot be read; the message names the file.
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ResultFolderError(f"{out}: is a file, not a result folder")
    for name in ("config.yaml", "results.csv", "provenance.json"):
        if not (out / name).is_file():
            hint = (
                "an unfinished run: rerun it with the same config to finish"
                if (out / "config.yaml").is_file()
                else "run `simlunar run EXPERIMENT.yaml` first"
            )
            raise ResultFolderError(f"{out}: not a result folder (missing {name}); {hint}")

    config = read_folder_config(out / "config.yaml")
    prov = _read_provenance(out / "provenance.json")
    for name, digest in (prov.get("files") or {}).items():
        path = out / name
        if not path.is_file() or file_sha256(path) != digest:
            raise ResultFolderError(
                f"{path}: does not belong to this folder's results (changed or missing since "
                "provenance.json was written); rerun the experiment into this folder to repair"
            )
    rows = _read_rows(out / "results.csv")
    cache = UnitCache(out)
    units = []
    for key in prov["unit_keys"]:
        rec = cache.load(key)
        if rec is None:
            raise ResultFolderError(
                f"{cache.json_path(key)}: unit missing or unreadable; rerun the experiment "
                "into this folder to recompute it"
            )
        units.append(rec)
    return {
        "config": config,
        "rows": rows,
        "units": units,
        "dir": out,
        "provenance": prov,
    }


def _read_provenance(path: Path) -> dict:
    try:
        prov = json.loads(path.read_text())
    except (ValueError, OSError) as exc:
        raise ResultFolderError(f"{path}: not valid JSON ({exc})") from None
    keys = prov.get("unit_keys") if isinstance(prov, dict) else None
    if not isinstance(keys, list) or not keys or not all(isinstance(k, str) for k in keys):
        raise ResultFolderError(f"{path}: no 'unit_keys' list; not a simlunar provenance file")
    return prov


def _read_rows(path: Path) -> list[dict[str, str]]:
    try:
        rows = read_csv(path)
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ResultFolderError(f"{path}: unreadable ({exc})") from None
    if not rows:
        raise ResultFolderError(f"{path}: no result rows")
    missing = [c for c in ("unit", "metric", "value") if c not in rows[0]]
    if missing:
        raise ResultFolderError(f"{path}: no {missing[0]!r} column; not a simlunar results table")
    for i, r in enumerate(rows, start=2):
        try:
            float(r["value"])
            int(r["unit"])
        except (TypeError, ValueError):
            raise ResultFolderError(
                f"{path}: line {i}: unit {r['unit']!r}, value {r['value']!r} are not numbers"
            ) from None
    return rows


def load_unit_arrays(out_dir: str | Path, index: int = 0) -> dict:
    """The arrays of unit ``index`` of a result folder (image, depth, wavelet_energy, ...)."""
    res = load_results(out_dir)
    rec = res["units"][index]
    return UnitCache(res["dir"]).load_arrays(rec["key"])


#: the figures' record of what they were drawn from (in the result folder, beside figures/)
STAMP = ".figures.json"
#: modules whose code draws the figures, a change of any of which redraws every figure: this
#: one and every module of ``simlunar.plotting`` and ``simlunar.results`` it imports, directly
#: or through one another (tests/results/test_figures.py derives that set from the sources and
#: fails when this list differs: a former list missed the landing tables and captions, and
#: derived at run time it cost every rerun 0.17 s)
DRAWING_MODULES = (
    "simlunar.plotting",
    "simlunar.plotting.density",
    "simlunar.plotting.figures",
    "simlunar.plotting.forest",
    "simlunar.plotting.headroom",
    "simlunar.plotting.images",
    "simlunar.plotting.landing",
    "simlunar.plotting.landing_tables",
    "simlunar.plotting.layout",
    "simlunar.plotting.lidar",
    "simlunar.plotting.lidar_tables",
    "simlunar.plotting.reconstructions",
    "simlunar.plotting.scanner",
    "simlunar.plotting.seed_stats",
    "simlunar.plotting.style",
    "simlunar.plotting.tables",
    "simlunar.results._drawing",
    "simlunar.results.aggregate",
    "simlunar.results.array_exports",
    "simlunar.results.cache_keys",
    "simlunar.results.captions",
    "simlunar.results.captions_landing",
    "simlunar.results.exports",
    "simlunar.results.figures",
    "simlunar.results.folder",
    "simlunar.results.lidar_exports",
    "simlunar.results.lidar_figures",
    "simlunar.results.md_tables",
    "simlunar.results.ply",
    "simlunar.results.records",
    "simlunar.results.sampling_figures",
    "simlunar.results.scanner_figures",
    "simlunar.results.store",
)


def figure_inputs(res: dict, formats) -> str:
    """SHA-256 of everything the figures of a result folder are drawn from: the tables
    (``results.csv`` and the summary files, as ``provenance.json`` records their digests), the
    units (their keys), the configuration (less its description), the file formats, the
    drawing code and the matplotlib version."""
    import hashlib
    import importlib.metadata
    import importlib.util

    cfg = {k: v for k, v in res["config"].items() if k not in ("description", "catalogue")}
    code = {}
    for mod in DRAWING_MODULES:
        spec = importlib.util.find_spec(mod)
        if spec is not None and spec.origin:
            code[mod] = file_sha256(spec.origin)
    blob = json.dumps(
        {
            "files": res["provenance"].get("files"),
            "units": res["provenance"].get("unit_keys"),
            "config": cfg,
            "formats": list(formats),
            "code": code,
            "matplotlib": importlib.metadata.version("matplotlib"),
        },
        sort_keys=True,
        default=str,
    )
    return hashlib.sha256(blob.encode()).hexdigest()


def _up_to_date(fig_dir: Path, digest: str) -> list[Path] | None:
    """The figure files of ``fig_dir`` when the stamp records ``digest`` and they all exist."""
    try:
        stamp = json.loads((fig_dir.parent / STAMP).read_text())
        names = list(stamp["files"])
        if stamp["inputs"] != digest:
            return None
    except (OSError, ValueError, KeyError, TypeError):
        return None
    paths = [fig_dir / n for n in names]
    return paths if all(p.is_file() for p in paths) else None


def write_figures(out_dir: str | Path, *, formats=None, force: bool = False) -> list[Path]:
    """Draw every figure the results support; returns the paths of the figure files.

    Figures are drawn only when their inputs (:func:`figure_inputs`) changed since they were
    last drawn (``.figures.json``), or with ``force``; ``formats`` (default: the
    folder's ``figures.formats``, PNG) names the files per figure.
    """
    res = load_results(out_dir)
    out = res["dir"]
    cfg = res["config"]
    formats = list(formats or (cfg.get("figures") or {}).get("formats") or ["png"])
    fig_dir = out / "figures"
    digest = figure_inputs(res, formats)
    if not force:
        kept = _up_to_date(fig_dir, digest)
        if kept is not None:
            return kept
    # a damaged unit is reported before anything of the folder changes
    cache = UnitCache(out)
    for rec in res["units"]:
        if not cache.arrays_readable(rec["key"]):
            cache.load_arrays(rec["key"], strict=True)  # raises, naming the file
    (out / STAMP).unlink(missing_ok=True)  # figures being redrawn belong to no inputs
    written = _draw(res, formats)
    atomic_write_bytes(
        out / STAMP,
        json.dumps({"inputs": digest, "files": [p.name for p in written]}, indent=1).encode(),
    )
    return written


def _draw(res: dict, formats: list[str]) -> list[Path]:
    """Draw the figures of the folder's study kind into ``figures/`` with their captions;
    returns the files written."""
    # the drawing modules import matplotlib: imported when a figure is drawn, not by every
    # importer of this module (the runner, even with --no-figures; the fit; notebooks)
    from simlunar.results._drawing import draw

    written, captions = draw(res, formats)
    write_captions(res["dir"] / "figures", captions, written)
    return written


#: the file of ``figures/`` that names the figures not drawn and why
NOT_DRAWN = "not_drawn.md"


def write_captions(fig_dir: Path, captions: dict[str, str], written: list[Path]) -> None:
    """Write ``figures/captions.md``: one section per figure (stem), its caption beside it;
    and, when ``captions`` names figures not drawn (``captions.not_drawn``, see
    :class:`simlunar.results.captions.Captions`), ``figures/not_drawn.md`` in the same form,
    each figure's reason beside it."""
    sections = (("captions.md", "Figure captions", captions),
                (NOT_DRAWN, "Figures not drawn", getattr(captions, "not_drawn", {})))  # fmt: skip
    for name, title, texts in sections:
        if not texts:
            continue
        lines = [f"# {title}", ""]
        for stem, text in texts.items():
            lines += [f"## {stem}", "", text, ""]
        path = fig_dir / name
        atomic_write_bytes(path, "\n".join(lines).encode())
        written.append(path)


def write_figures_pruned(out_dir: str | Path, *, formats=None, force: bool = False) -> list[Path]:
    """:func:`write_figures`, then remove the figures of ``figures/`` it did not write."""
    written = write_figures(out_dir, formats=formats, force=force)
    prune_figures(Path(out_dir), keep=written)
    return written
