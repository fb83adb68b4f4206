"""Paper figures from tidy results and unit arrays (matplotlib only): one namespace.

Every function returns ``(Figure, Axes)`` (or an array of Axes for panels) and accepts ``ax=``
to draw into an existing axes, so figures compose into multi-panel layouts. The functions live
by subject: :mod:`~simlunar.plotting.layout` (sizes, grids, legends, saving),
:mod:`~simlunar.plotting.density` (error and score curves), :mod:`~simlunar.plotting.images`
(image panels, Fig. 4) and :mod:`~simlunar.plotting.scanner` (scanner study).
"""

from __future__ import annotations

from simlunar.planner import PAPER_STRATEGIES
from simlunar.plotting.density import (
    BAND_LABEL,
    BAND_LABEL_SEEDS,
    density_axis,
    density_label,
    error_vs_density,
    mean_error_by_density,
    ratio_axis,
    samples_saved_plot,
    score_vs_sweep,
)
from simlunar.plotting.headroom import headroom_plot
from simlunar.plotting.images import (
    DEPTH_CMAP,
    SAMPLE_INK,
    PanelText,
    image_panels,
    sample_marker_area,
    sparse_mesh_panels,
)
from simlunar.plotting.layout import (
    COLUMN_W,
    MAX_COLS,
    PAGE_W,
    close,
    legend_outside,
    panel_grid,
    panel_row,
    save,
    shared_legend,
)
from simlunar.plotting.scanner import (
    bit_error_rates,
    error_scale,
    scanner_bars,
    scanner_relative_bars,
    scanner_vs_sweep,
)
from simlunar.plotting.style import style

#: fixed colours so a strategy looks the same in every figure (see simlunar.plotting.style)
STRATEGY_COLORS = {n: style(n).colour for n in (*PAPER_STRATEGIES, "saliency")}

__all__ = [
    "BAND_LABEL",
    "BAND_LABEL_SEEDS",
    "COLUMN_W",
    "DEPTH_CMAP",
    "MAX_COLS",
    "PAGE_W",
    "SAMPLE_INK",
    "STRATEGY_COLORS",
    "PanelText",
    "bit_error_rates",
    "close",
    "density_axis",
    "density_label",
    "error_scale",
    "error_vs_density",
    "headroom_plot",
    "image_panels",
    "legend_outside",
    "mean_error_by_density",
    "panel_grid",
    "panel_row",
    "ratio_axis",
    "sample_marker_area",
    "samples_saved_plot",
    "save",
    "scanner_bars",
    "scanner_relative_bars",
    "scanner_vs_sweep",
    "score_vs_sweep",
    "shared_legend",
    "sparse_mesh_panels",
]
