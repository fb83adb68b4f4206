"""A result folder's own files: its configuration and its figures."""

from __future__ import annotations

from pathlib import Path

from simlunar.config.yamlio import YAMLError, safe_load_text
from simlunar.errors import ResultFolderError

__all__ = ["prune_figures", "read_folder_config"]


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
    """Remove ``figures/*.png|pdf`` not in ``keep`` (figures of another state of the folder)."""
    keep = {Path(p).name for p in keep}
    fig_dir = out / "figures"
    removed = []
    if fig_dir.is_dir():
        for p in sorted(fig_dir.iterdir()):
            if p.suffix.lower() in (".png", ".pdf") and p.name not in keep and p.is_file():
                p.unlink()
                removed.append(p)
    return removed
