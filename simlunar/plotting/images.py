"""Image panels of one unit: guide image, wavelet energy, samples, truth, reconstruction and
error (the sampling study's panels), and the sparse-mesh renders of the paper's Fig. 4.

Panels of a nadir orthographic view, where a pixel is a terrain cell, are drawn in metres
(``spacing_m``); other views in pixels. Figure heights follow the image's aspect ratio.
"""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np

from simlunar.planner import DEFAULT_PLANNER
from simlunar.plotting.layout import LABEL_PT, PAGE_W, TICK_PT, TITLE_PT
from simlunar.plotting.style import label

__all__ = [
    "DEPTH_CMAP",
    "SAMPLE_INK",
    "PanelText",
    "image_panels",
    "sample_marker_area",
    "sparse_mesh_panels",
]

#: colour map of depth (perceptually uniform; no land/water reading as "terrain" had)
DEPTH_CMAP = "cividis"
#: at most this share of a samples panel is covered by sample markers (the rest shows the
#: image under them, so where samples concentrate stays visible at any density)
SAMPLE_INK = 0.15


def _extent(shape, spacing_m):
    if not spacing_m:
        return None
    rows, cols = shape[:2]
    return (0.0, cols * spacing_m, rows * spacing_m, 0.0)


def _show(ax, img, title, cmap="gray", *, extent=None, **kw):
    im = ax.imshow(img, cmap=cmap, interpolation="nearest", extent=extent, **kw)
    ax.set_title(title, fontsize=TITLE_PT - 1)
    if extent is None:
        ax.set_xticks([])
        ax.set_yticks([])
    else:
        ax.tick_params(labelsize=TICK_PT - 1.5, length=2, pad=1)
    return im


def _metre_labels(axes, left, bottom) -> None:
    """``x (m)`` under the bottom panels, ``y (m)`` beside the left ones; tick labels of the
    inner panels hidden (all panels share the extent)."""
    for i, ax in enumerate(axes):
        if i in bottom:
            ax.set_xlabel("x (m)", fontsize=LABEL_PT - 1, labelpad=1)
        else:
            ax.tick_params(labelbottom=False)
        if i in left:
            ax.set_ylabel("y (m)", fontsize=LABEL_PT - 1, labelpad=1)
        else:
            ax.tick_params(labelleft=False)


def _cbar(fig, im, ax, text):
    cb = fig.colorbar(im, ax=ax, shrink=0.85, pad=0.02, aspect=15)
    cb.set_label(text, fontsize=TICK_PT - 1)
    cb.ax.tick_params(labelsize=TICK_PT - 1.5)
    return cb


def _panel_height(shape, per_row_w: float, rows: int, extra: float) -> float:
    h, w = shape[:2]
    return float(np.clip(rows * (per_row_w * h / max(w, 1) + extra) + 0.25, 2.0, 9.0))


def sample_marker_area(ax, k: int, *, ink: float = SAMPLE_INK) -> float:
    """Scatter marker area (pt²) for ``k`` samples on ``ax``: ``ink`` of the axes' area over
    ``k``, between 0.05 pt² (a dot still visible at 300 dpi) and 4 pt² (few samples)."""
    w, h = ax.bbox.width, ax.bbox.height  # display pixels at the figure's dpi
    area_pt2 = w * h * (72.0 / ax.figure.dpi) ** 2
    return float(np.clip(ink * area_pt2 / max(int(k), 1), 0.05, 4.0))


def _log_energy(energy) -> np.ndarray:
    e = np.asarray(energy, float)
    pos = e[e > 0]
    floor = float(np.percentile(pos, 1)) if pos.size else 1e-12
    return np.log10(np.maximum(e, floor))


def _hull(ax, rows, cols, spacing_m) -> None:
    """The convex hull of the samples (dashed): outside it the reconstruction extrapolates."""
    from scipy.spatial import ConvexHull, QhullError

    pts = np.column_stack([np.asarray(cols, float), np.asarray(rows, float)])
    if len(pts) < 3:
        return
    try:
        hull = ConvexHull(pts)
    except QhullError:
        return
    v = pts[np.r_[hull.vertices, hull.vertices[:1]]]
    if spacing_m:
        v = (v + 0.5) * spacing_m  # pixel centres in metres
    ax.plot(v[:, 0], v[:, 1], color="k", lw=0.6, ls="--")


@dataclass(frozen=True)
class PanelText:
    """The words of :func:`image_panels`.

    Attributes
    ----------
    density_label : str
        Sweep-independent density text for the samples panel, e.g. ``"k/N = 1/32"``.
    planner : str
        Strategy that placed the samples (its display label titles the samples panel).
    point : str
        Sweep point or scene the panels show (figure title), e.g. ``"sun elevation 30 deg"``.
    """

    density_label: str = ""
    planner: str = DEFAULT_PLANNER
    point: str = ""


def image_panels(
    image: np.ndarray,
    energy: np.ndarray,
    samples: tuple[np.ndarray, np.ndarray],
    reconstruction: np.ndarray,
    truth: np.ndarray,
    *,
    axes=None,
    text: PanelText = PanelText(),
    spacing_m: float | None = None,
):
    """Guide image, wavelet energy map, sample locations, truth, reconstruction and error map.

    Panels (2 x 3): guide image | wavelet energy (log10, colour bar) | the planner's samples on
    the guide image; true depth | reconstruction (same colour scale, colour bar in m) | error
    reconstruction - truth (m, symmetric scale at the 99th percentile of |error|), with the
    samples' convex hull dashed (outside it the reconstruction takes the nearest sample).

    Parameters
    ----------
    image : (rows, cols) float
        Guide (sensor) image.
    energy : (rows, cols) float
        Frequency map (wavelet energy), shown on a log scale.
    samples : (plan_rows, plan_cols), two (k,) int arrays
        Sampled pixels.
    reconstruction, truth : (rows, cols) float
        Reconstructed and true depth from the camera (m); the error map is their difference.
    axes : sequence of 6 Axes, optional
    text : PanelText
        The density label, the planner's name and the figure title.
    spacing_m : float, optional
        Cell size of a nadir orthographic view (pixel = cell): axes in metres; None = pixels.

    Returns
    -------
    (Figure, ndarray of Axes)
    """
    plan_rows, plan_cols = samples
    ext = _extent(np.shape(image), spacing_m)
    fig, axes = _panel_axes(axes, np.shape(image), ext)
    top = max(float(np.nanmax(image)), 1e-12)
    im = _show(axes[0], image, "guide image", extent=ext, vmin=0, vmax=top)
    _cbar(fig, im, axes[0], "sensor value (0-1)")
    im = _show(axes[1], _log_energy(energy), "wavelet energy", cmap="magma", extent=ext)
    _cbar(fig, im, axes[1], "log10 energy")
    dens = f", {text.density_label.strip('() ')}" if text.density_label else ""
    _show(axes[2], image, f"{label(text.planner)} samples{dens}", extent=ext, vmin=0, vmax=top)
    k = _scatter_samples(axes[2], plan_rows, plan_cols, spacing_m if ext is not None else None)
    _depth_panels(fig, axes[3:5], truth, reconstruction, f"reconstruction ({k} samples)", ext)
    im = _error_panel(axes[5], reconstruction, truth, ext)
    _hull(axes[5], plan_rows, plan_cols, spacing_m if ext is not None else None)
    _cbar(fig, im, axes[5], "error (m)")
    if ext is not None:
        _metre_labels(axes, left={0, 3}, bottom={3, 4, 5})
    if text.point:
        fig.suptitle(text.point, fontsize=TITLE_PT)
    return fig, axes


def _panel_axes(axes, shape, ext):
    """The figure and the six axes of :func:`image_panels` (new ones unless given)."""
    if axes is None:
        extra = 0.5 if ext is not None else 0.3
        fig, axes = plt.subplots(
            2,
            3,
            figsize=(PAGE_W, _panel_height(shape, 1.45, 2, extra)),
            constrained_layout=True,
        )
        # a gap after each colour bar, so its label does not read as the next panel's y label
        fig.get_layout_engine().set(wspace=0.12)
    else:
        fig = axes[0].figure if isinstance(axes, (list, tuple)) else np.ravel(axes)[0].figure
    axes = np.asarray(axes).ravel()
    if len(axes) < 6:
        raise ValueError(f"axes: 6 panels need 6 axes, got {len(axes)}")
    return fig, axes


def _scatter_samples(ax, plan_rows, plan_cols, spacing_m) -> int:
    """The sampled pixels as dots over the image (pixel centres in metres when
    ``spacing_m``); returns their number."""
    k = len(np.asarray(plan_rows))
    xy = np.column_stack([np.asarray(plan_cols), np.asarray(plan_rows)])
    if spacing_m:
        xy = (xy + 0.5) * spacing_m
    ax.scatter(
        xy[:, 0],
        xy[:, 1],
        s=sample_marker_area(ax, k),
        c="#d62728",
        linewidths=0,
        rasterized=k > 2000,  # a PDF of tens of thousands of vector dots is slow to open
    )
    return k


def _depth_panels(fig, axes, truth, reconstruction, title, ext) -> None:
    """True depth and reconstruction on one colour scale, one colour bar for both."""
    vmin, vmax = float(np.nanmin(truth)), float(np.nanmax(truth))
    _show(axes[0], truth, "true depth", cmap=DEPTH_CMAP, extent=ext, vmin=vmin, vmax=vmax)
    im = _show(axes[1], reconstruction, title, cmap=DEPTH_CMAP, extent=ext, vmin=vmin, vmax=vmax)
    _cbar(fig, im, axes.tolist(), "depth (m)")


def _error_panel(ax, reconstruction, truth, ext):
    """Reconstruction - truth on a symmetric scale at the 99th percentile of |error|."""
    err = np.asarray(reconstruction, float) - np.asarray(truth, float)
    lim = float(np.nanpercentile(np.abs(err), 99)) or 1e-12
    return _show(
        ax,
        err,
        "error: reconstruction - truth\n(dashed: samples' hull)",
        cmap="coolwarm",
        extent=ext,
        vmin=-lim,
        vmax=lim,
    )


def _mesh_layout(n: int, shape, rough: bool):
    """Axes of the sparse-mesh figure in panel order; renders in the top row, maps centred
    below (no empty grid cell)."""
    if n <= 3:
        fig, grid = plt.subplots(
            1, n, figsize=(PAGE_W, _panel_height(shape, PAGE_W / n - 0.6, 1, 0.6)),
            constrained_layout=True, squeeze=False,
        )  # fmt: skip
        return fig, list(grid[0])
    fig = plt.figure(
        figsize=(PAGE_W, _panel_height(shape, PAGE_W / 3 - 0.5, 2, 0.45)), constrained_layout=True
    )
    gs = fig.add_gridspec(2, 6)
    top = [fig.add_subplot(gs[0, 2 * i : 2 * i + 2]) for i in range(3)]
    maps = n - 3  # the difference (with rough) and the energy map
    start = 3 - maps
    bottom = [fig.add_subplot(gs[1, start + 2 * i : start + 2 * i + 2]) for i in range(maps)]
    if rough:  # panel order: rough, difference, constant, full, energy
        return fig, [top[0], bottom[0], top[1], top[2], *bottom[1:]]
    return fig, [*top, *bottom]


def sparse_mesh_panels(
    sparse: np.ndarray,
    full: np.ndarray,
    energy: np.ndarray | None = None,
    *,
    rough: np.ndarray | None = None,
    axes=None,
    n_samples: int | None = None,
    point: str = "",
    spacing_m: float | None = None,
):
    """Paper Fig. 4: sparse-mesh renderings next to the full-resolution ground truth.

    Panels (in the returned order): the sparse mesh with roughness modulated by wavelet
    energy and the difference of that render from the constant-roughness one (when ``rough``
    is given), the sparse mesh with constant roughness, the full-resolution render, and the
    frequency map (when ``energy`` is given). Renders in the top row, the two maps below. All
    renders share one exposure (the 99.5th percentile of ``full``), so brightness differences
    are real; the difference panel is in units of that exposure, on a symmetric scale at the
    99th percentile of |difference| (a few extreme pixels would flatten it otherwise).

    Parameters
    ----------
    sparse, full : (rows, cols) or (rows, cols, 3) float
        Renders of the reconstructed (sparse) mesh with constant roughness and of the
        full-resolution terrain, linear.
    energy : (rows, cols) float, optional
        The frequency map that modulated the roughness (log scale).
    rough : (rows, cols) or (rows, cols, 3) float, optional
        Render of the sparse mesh with per-cell roughness from ``energy``, linear.
    axes : sequence of Axes, optional
        One per panel.
    n_samples : int, optional
        Number of samples of the sparse mesh (shown in the titles).
    point : str
        Sweep point or scene (figure title).
    spacing_m : float, optional
        Cell size of a nadir orthographic view: axes in metres; None = pixels.
    """
    n = 2 + 2 * (rough is not None) + (energy is not None)
    ext = _extent(np.shape(full), spacing_m)
    if axes is None:
        fig, axes = _mesh_layout(n, np.shape(full), rough is not None)
    else:
        fig = np.ravel(axes)[0].figure
    axes = list(np.asarray(axes).ravel())
    if len(axes) < n:
        raise ValueError(f"axes: {n} panels need {n} axes, got {len(axes)}")
    top = max(float(np.nanpercentile(full, 99.5)), 1e-12)
    label_ = f"sparse mesh ({n_samples} samples)" if n_samples else "sparse mesh"
    i = 0
    if rough is not None:
        _roughness_panels(fig, axes[i : i + 2], rough, sparse, top, label_, ext)
        i += 2
    _show(axes[i], np.clip(sparse / top, 0, 1), f"{label_},\nconstant roughness", extent=ext)
    _show(axes[i + 1], np.clip(full / top, 0, 1), "full resolution", extent=ext)
    if energy is not None:
        im = _show(axes[i + 2], _log_energy(energy), "frequency map", cmap="magma", extent=ext)
        _cbar(fig, im, axes[i + 2], "log10 wavelet energy")
    if ext is not None:
        _mesh_metre_labels(axes[:n])
    if point:
        fig.suptitle(point, fontsize=TITLE_PT)
    return fig, np.asarray(axes[:n])


def _roughness_panels(fig, axes, rough, sparse, top, title, ext) -> None:
    """The render with roughness from energy, and its difference from the constant-roughness
    render (in units of the exposure ``top``, symmetric at the 99th percentile)."""
    _show(axes[0], np.clip(rough / top, 0, 1), f"{title},\nroughness from energy", extent=ext)
    diff = np.asarray(rough, float) / top - np.asarray(sparse, float) / top
    if diff.ndim == 3:
        diff = diff.mean(axis=2)
    lim = float(np.nanpercentile(np.abs(diff), 99)) or 1e-12
    im = _show(
        axes[1],
        diff,
        "energy - constant roughness",
        cmap="coolwarm",
        extent=ext,
        vmin=-lim,
        vmax=lim,
    )
    _cbar(fig, im, axes[1], "Δ radiance / exposure\n(clipped at 99th pct.)")


def _mesh_metre_labels(axes) -> None:
    """``x (m)`` under every panel; ``y (m)`` on the first panel of each row (the rough
    render and the difference when there are two rows)."""
    firsts = {0, 1} if len(axes) > 3 else {0}
    for j, ax in enumerate(axes):
        ax.set_xlabel("x (m)", fontsize=LABEL_PT - 1, labelpad=1)
        if j in firsts:
            ax.set_ylabel("y (m)", fontsize=LABEL_PT - 1, labelpad=1)
