"""A result folder: one configuration per folder (``config.yaml``), its summary files, its
scans and figures; checks that it can be written before anything finished is removed."""

from __future__ import annotations

import json
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any

from simlunar.config.yamlio import YAMLError, safe_load_text
from simlunar.errors import ResultFolderError
from simlunar.results.array_exports import array_export_complete
from simlunar.results.cache_keys import (
    render_without_new_defaults,
    terrain_without_new_defaults,
    without_new_defaults,
)
from simlunar.results.exports import export_complete
from simlunar.results.md_tables import TABLES_DIR
from simlunar.results.records import WorkUnit
from simlunar.results.store import (
    atomic_write_text,
    file_sha256,
)

__all__ = [
    "RESULT_FILES",
    "array_folders",
    "claim_folder",
    "folder_complete",
    "prune_figures",
    "prune_scans",
    "read_folder_config",
    "scan_folders",
]


def read_folder_config(path: Path) -> dict:
    """A result folder's ``config.yaml`` as a dict (:class:`ResultFolderError` if unreadable)."""
    try:
        data = safe_load_text(path.read_text())
    except (YAMLError, UnicodeDecodeError, OSError) as exc:
        what = "not valid YAML" if isinstance(exc, YAMLError) else "unreadable"
        raise ResultFolderError(
            f"{path}: {what}, so the folder's configuration is unknown; "
            "choose another --out or delete the folder"
        ) from None
    if not isinstance(data, dict) or not isinstance(data.get("study"), dict):
        raise ResultFolderError(
            f"{path}: not an experiment configuration; choose another --out or delete the folder"
        )
    return data


def prune_figures(out: Path, keep) -> list[Path]:
    """Remove ``figures/*.png|pdf`` not in ``keep`` (figures of another state of the folder),
    and ``figures/captions.md`` unless kept (captions of figures no longer there would
    describe what the report does not show)."""
    keep = {Path(p).name for p in keep}
    fig_dir = out / "figures"
    removed = []
    if fig_dir.is_dir():
        for p in sorted(fig_dir.iterdir()):
            if p.suffix.lower() in (".png", ".pdf") and p.name not in keep and p.is_file():
                p.unlink()
                removed.append(p)
        captions = fig_dir / "captions.md"
        if captions.name not in keep and captions.is_file():
            captions.unlink()
    return removed


def _remove_empty(out: Path) -> None:
    try:
        out.rmdir()
    except OSError:
        pass


def _first_difference(old: Any, new: Any, path: str = "") -> str:
    """``key.path: <old> here, <new> now`` for the first difference of two plain configs."""
    if isinstance(old, dict) and isinstance(new, dict):
        for k in list(old) + [k for k in new if k not in old]:
            if old.get(k, "<absent>") != new.get(k, "<absent>"):
                return _first_difference(
                    old.get(k, "<absent>"), new.get(k, "<absent>"), f"{path}.{k}" if path else k
                )
    return f"{path or '<root>'}: {json.dumps(old, default=str)} in the folder, {json.dumps(new, default=str)} now"


def _identity(config: dict) -> dict:
    """The part of a plain config that a result folder belongs to: all but the description
    and the catalogue block (what the experiment shows, its run time), the figure file formats (they change no unit, table or figure content) and study keys
    added later at the value that changes nothing (a folder written before them is the same
    experiment)."""
    out = {k: v for k, v in config.items() if k not in ("description", "catalogue")}
    if isinstance(out.get("study"), dict):  # keys added later, at their no-change default
        out["study"] = without_new_defaults(out["study"])
    if isinstance(out.get("render"), dict):
        out["render"] = render_without_new_defaults(out["render"])
    if isinstance(out.get("terrain"), dict):
        out["terrain"] = terrain_without_new_defaults(out["terrain"])
    if isinstance(out.get("figures"), dict):
        out["figures"] = {k: v for k, v in out["figures"].items() if k != "formats"}
    return out


def claim_folder(out: Path, config_text: str) -> None:
    """Make ``out`` the folder of this configuration, or refuse (nothing is written then).

    A folder with a ``config.yaml`` takes only that same configuration (a resume or a rerun);
    a folder without one must be empty (hidden files aside). The new ``config.yaml`` is
    written only into an empty folder.
    """
    path = out / "config.yaml"
    new = safe_load_text(config_text)
    if path.exists():
        old = read_folder_config(path)
        if _identity(old) != _identity(new):
            raise ResultFolderError(
                f"{out} holds the results of another configuration "
                f"({_first_difference(old, new)}); choose another --out or delete the folder"
            )
        if path.read_text() != config_text:
            # same results: written by an older version, or another description or figure
            # file format (which change no number)
            atomic_write_text(path, config_text)
        return
    others = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    if others:
        raise ResultFolderError(
            f"{out}: not empty and not a simlunar result folder (no config.yaml, found "
            f"{others[0]}); choose an empty or new folder"
        )
    atomic_write_text(path, config_text)


#: files that summarise the units; removed before the units change, written again at the end
#: (provenance.json first: without it the folder reads as unfinished)
RESULT_FILES = (
    "provenance.json", "results.csv", "scores.md", "scores.tex", "scores.csv",
    "samples_saved.csv", "reconstructions.csv",
)  # fmt: skip


def folder_complete(out: Path, keys: list[str], *, ignore=()) -> bool:
    """Whether the summary files are present and belong to these units and this config
    (``ignore``: files whose digest is not compared, e.g. ``config.yaml`` when only an
    export flag changed it)."""
    try:
        prov = json.loads((out / "provenance.json").read_text())
        files = prov["files"]
        if prov["unit_keys"] != keys:
            return False
        return all(
            file_sha256(out / name) == digest
            for name, digest in files.items()
            if name not in ignore
        )
    except (OSError, ValueError, KeyError, TypeError):
        return False


def _invalidate(out: Path) -> None:
    for name in RESULT_FILES:
        (out / name).unlink(missing_ok=True)
    shutil.rmtree(out / TABLES_DIR, ignore_errors=True)  # the CSV copies of scores.md's tables
    prune_figures(out, keep=())


def _export_folders(units: list[WorkUnit], flag: str) -> dict[str, str]:
    """``{"unit<i>": unit key}`` of the units whose study section sets ``flag`` (of units
    sharing a key, the first, which is the one computed)."""
    out: dict[str, str] = {}
    seen: set[str] = set()
    for u in units:
        if (u.config.get("study") or {}).get(flag) and u.key not in seen:
            seen.add(u.key)
            out[f"unit{u.index}"] = u.key
    return out


def scan_folders(units: list[WorkUnit]) -> dict[str, str]:
    """``{"unit<i>": unit key}``: the ``scans/`` folders these units export (units with
    ``study.save_scans``; of units sharing a key, the first, which is the one computed)."""
    return _export_folders(units, "save_scans")


def array_folders(units: list[WorkUnit]) -> dict[str, str]:
    """``{"unit<i>": unit key}``: the ``arrays/`` folders these units export (units with
    ``study.save_arrays``; of units sharing a key, the first, which is the one computed)."""
    return _export_folders(units, "save_arrays")


def _scans_present(out: Path, scan_dirs: dict[str, str], u: WorkUnit, sub: str = "scans") -> bool:
    name = f"unit{u.index}"
    if scan_dirs.get(name) != u.key:
        return True  # exports nothing (or a unit of the same key does)
    complete = array_export_complete if sub == "arrays" else export_complete
    return complete(out / sub / name, u.key)


def prune_scans(out: Path, scan_dirs: dict[str, str], sub: str = "scans") -> list[Path]:
    """Remove ``scans/unit<i>/`` folders (``sub="arrays"``: ``arrays/unit<i>/``) that do not
    hold the export of the unit that now has index i (another configuration's, an
    interrupted one, or save_scans / save_arrays turned off)."""
    folder = out / sub
    complete = array_export_complete if sub == "arrays" else export_complete
    removed: list[Path] = []
    if not folder.is_dir():
        return removed
    for p in sorted(folder.iterdir()):
        if not (p.is_dir() and re.fullmatch(r"unit\d+", p.name)):
            continue  # only what the runner writes
        key = scan_dirs.get(p.name)
        if key is None or not complete(p, key):
            shutil.rmtree(p)
            removed.append(p)
    if not any(folder.iterdir()):
        folder.rmdir()
    return removed


def _read_provenance(out: Path) -> dict:
    try:
        prov = json.loads((out / "provenance.json").read_text())
    except (OSError, ValueError):
        return {}
    return prov if isinstance(prov, dict) else {}


def _check_writable(out: Path, scan_dirs: dict[str, str], array_dirs=None) -> None:
    """Write (and remove) a small file in each folder the run writes into, so a full disk,
    a quota or a folder made read-only fails here (exit 3) before any result is deleted."""
    folders = [out, out / "units", out / "figures"] + ([out / "scans"] if scan_dirs else [])
    folders += [out / "arrays"] if array_dirs else []
    for d in folders:
        if d.exists() and not d.is_dir():
            raise ResultFolderError(f"--out {out}: {d} is not a folder")
        target = d if d.is_dir() else out
        try:
            fd, tmp = tempfile.mkstemp(prefix=".simlunar-probe.", dir=target)
        except OSError as exc:
            raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from exc
        try:
            os.write(fd, b"\0" * 65536)
            os.fsync(fd)
        except OSError as exc:
            raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from exc
        finally:
            os.close(fd)
            os.unlink(tmp)
