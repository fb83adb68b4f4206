"""The drawing of a result folder's figures, one module per study kind (they import
Matplotlib): :func:`simlunar.results.figures.write_figures` imports this module only when it
draws, so its other importers (the runner, even with ``--no-figures``; the fit; notebooks)
load no Matplotlib."""

from __future__ import annotations

from pathlib import Path

from simlunar.plotting.figures import close, save
from simlunar.results import lidar_figures, sampling_figures, scanner_figures
from simlunar.results.captions import Captions
from simlunar.results.store import atomic_write_bytes

__all__ = ["draw"]


def draw(res: dict, formats: list[str]) -> tuple[list[Path], Captions]:
    """Draw the figures of the folder's study kind into ``figures/``.

    Parameters
    ----------
    res : dict
        The folder's results (:func:`simlunar.results.figures.load_results`).
    formats : list of str
        File formats per figure (``png``, ``pdf``).

    Returns
    -------
    (list of Path, Captions)
        The files written, and the caption of each figure stem (with the figures not
        drawn and why, :attr:`Captions.not_drawn`).
    """
    fig_dir = res["dir"] / "figures"
    written: list[Path] = []

    def emit(fig, stem):
        for suffix, data in save(fig, stem, formats):
            path = fig_dir / f"{stem}.{suffix}"
            atomic_write_bytes(path, data)
            written.append(path)
        close(fig)

    figures_of_kind = {
        "sampling": sampling_figures.sampling_figures,
        "scanner": scanner_figures.scanner_figures,
        "lidar": lidar_figures.lidar_figures,
    }[res["config"].get("study", {}).get("kind", "sampling")]
    captions = Captions()
    figures_of_kind(res, emit, captions)
    return written, captions
