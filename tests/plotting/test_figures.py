"""The figures namespace (simlunar.plotting.figures): the subject modules' functions under one
name; panel grids and shared legends through it."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import pytest

from simlunar.plotting import figures as F


def rows():
    out = []
    for s, scale in (("random", 2.0), ("wavelet", 1.0)):
        for d in (0.5, 0.25, 0.125):
            for t, noise in enumerate((0.9, 1.1)):
                out.append(
                    {
                        "strategy": s,
                        "density": str(d),
                        "trial": str(t),
                        "metric": "mse",
                        "value": str(scale / d * noise),
                        "unit": "0",
                    }
                )
    return out


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_panel_grid_wraps_rows_and_keeps_column_width():
    fig, axes = F.panel_grid(5)
    assert len(axes) == 5 and len(fig.axes) == 5  # the sixth grid cell is removed
    w, h = fig.get_size_inches()
    assert w == pytest.approx(3 * F.COLUMN_W) and h == pytest.approx(2 * 2.6)
    specs = [(a.get_subplotspec().rowspan.start, a.get_subplotspec().colspan.start) for a in axes]
    assert specs == [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1)]
    fig, axes = F.panel_grid(2)
    assert fig.get_size_inches()[0] == pytest.approx(2 * F.COLUMN_W)
    with pytest.raises(ValueError, match="at least one panel"):
        F.panel_grid(0)


def test_shared_legend_replaces_panel_legends_and_inner_labels():
    fig, axes = F.panel_grid(5)
    for ax in axes:
        F.error_vs_density(rows(), metric="mse", ax=ax, band_label=F.BAND_LABEL_SEEDS)
    F.shared_legend(fig, axes)
    assert all(ax.get_legend() is None for ax in axes)
    # the legend fills the grid's free sixth cell (no empty slot, nothing on the data)
    (slot,) = [ax for ax in fig.axes if ax not in axes]
    assert slot.get_subplotspec().rowspan.start == 1 and slot.get_subplotspec().colspan.start == 2
    leg = slot.get_legend()
    assert [t.get_text() for t in leg.get_texts()] == ["Random", "Wavelet", F.BAND_LABEL_SEEDS]
    ylabels = [ax.get_ylabel() for ax in axes]
    assert ylabels == ["MSE error (m²)", "", "", "MSE error (m²)", ""]
    # x labels on the bottom panel of each column: (1, 0), (1, 1) and (0, 2)
    xlabels = [bool(ax.get_xlabel()) for ax in axes]
    assert xlabels == [False, False, True, True, True]
    F.save(fig, "x", ("png",))  # the outside legend lays out


def test_shared_legend_keeps_labels_of_panels_with_different_quantities():
    fig, axes = F.panel_grid(2)
    F.error_vs_density(rows(), metric="mse", ax=axes[0])
    F.error_vs_density(rows(), metric="mse", ax=axes[1])
    axes[1].set_ylabel("GRAD error (m²)")
    F.shared_legend(fig, axes, prune_labels=False)
    assert [a.get_ylabel() for a in axes] == ["MSE error (m²)", "GRAD error (m²)"]


def test_the_namespace_is_the_subject_modules_functions():
    from simlunar.plotting import density, headroom, images, layout, scanner, style

    homes = (density, headroom, images, layout, scanner)
    for name in F.__all__:
        if name == "STRATEGY_COLORS":
            continue
        (home,) = [m for m in homes if name in m.__all__]  # one subject module exports it
        assert getattr(F, name) is getattr(home, name), name
    assert F.STRATEGY_COLORS["wavelet"] == style.style("wavelet").colour
    assert len(set(F.STRATEGY_COLORS.values())) == len(F.STRATEGY_COLORS)  # distinct colours
