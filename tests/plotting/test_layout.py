"""Figure layout: sizes by the panel count, free grid cells for the legend, one legend outside
the data, axis labels pruned to the outer panels, byte-identical saves."""

from __future__ import annotations

import matplotlib.pyplot as plt
import pytest

from simlunar.plotting.layout import (
    COLUMN_W,
    LEGEND_PT,
    close,
    legend_outside,
    new_axes,
    panel_grid,
    panel_row,
    save,
    shared_legend,
)


@pytest.fixture(autouse=True)
def _close_all():
    yield
    plt.close("all")


def test_panel_row_is_one_column_wide_per_panel():
    fig, axes = panel_row(3)
    assert len(axes) == 3
    assert tuple(fig.get_size_inches()) == pytest.approx((3 * COLUMN_W, 2.6))
    fig, _ = panel_row(2, width=5.0, height=2.0)
    assert tuple(fig.get_size_inches()) == pytest.approx((5.0, 2.0))


def test_panel_grid_rows_of_three_and_its_free_cells():
    fig, axes = panel_grid(4)
    assert len(axes) == 4 and len(fig.axes) == 4  # the two unused cells are removed
    assert tuple(fig.get_size_inches()) == pytest.approx((3 * COLUMN_W, 2 * 2.6))
    assert fig._simlunar_free == [(1, 1), (1, 2)]
    fig, axes = panel_grid(2)
    assert fig._simlunar_free == [] and fig.get_size_inches()[0] == pytest.approx(2 * COLUMN_W)
    with pytest.raises(ValueError, match=r"^panel_grid needs at least one panel, got 0$"):
        panel_grid(0)


def _plot(ax, labels):
    for i, name in enumerate(labels):
        ax.plot([0, 1], [i, i + 1], label=name)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.legend()


def test_shared_legend_fills_the_free_cells_and_prunes_labels():
    fig, axes = panel_grid(4)
    for ax in axes:
        _plot(ax, ["random", "wavelet"])
    shared_legend(fig, axes)
    assert all(ax.get_legend() is None for ax in axes)
    slot = [ax for ax in fig.axes if ax not in axes]
    assert len(slot) == 1 and not slot[0].axison
    assert [t.get_text() for t in slot[0].get_legend().get_texts()] == ["random", "wavelet"]
    # y labels on the left column, x labels on each column's bottom panel: column 0 goes on to
    # the second row (panel 3), columns 1 and 2 end in the first (panels 1 and 2)
    assert [ax.get_ylabel() for ax in axes] == ["y", "", "", "y"]
    assert [ax.get_xlabel() for ax in axes] == ["", "x", "x", "x"]


def test_shared_legend_below_a_full_row_and_the_union_of_entries():
    fig, axes = panel_row(2)
    _plot(axes[0], ["grid"])
    _plot(axes[1], ["random", "grid"])
    shared_legend(fig, axes, union=True, prune_labels=False)
    (legend,) = fig.legends
    assert [t.get_text() for t in legend.get_texts()] == ["grid", "random"]
    assert legend.get_texts()[0].get_fontsize() == LEGEND_PT
    assert [ax.get_ylabel() for ax in axes] == ["y", "y"]


def test_legend_outside_goes_below_the_axes():
    fig, ax = new_axes(None, (3, 2))
    assert tuple(fig.get_size_inches()) == pytest.approx((3, 2))
    assert new_axes(ax, (9, 9)) == (fig, ax)
    legend_outside(ax)  # nothing labelled: no legend
    assert ax.get_legend() is None
    ax.plot([0, 1], label="a")
    ax.plot([0, 1], label="b")
    ax.plot([0, 1], label="c")
    legend_outside(ax, ncols=2)
    leg = ax.get_legend()
    assert (
        leg._ncols == 2
        and tuple(leg.get_bbox_to_anchor().transformed(ax.transAxes.inverted()).p0)[1] < 0
    )


def test_save_is_byte_identical_for_the_same_figure():
    def draw():
        fig, ax = new_axes(None, (2, 2))
        ax.plot([0, 1, 2], [1, 0, 1])
        return fig

    a = save(draw(), "x", formats=("png", "pdf"), dpi=50)
    b = save(draw(), "x", formats=("png", "pdf"), dpi=50)
    assert [fmt for fmt, _ in a] == ["png", "pdf"]
    assert a == b
    assert a[0][1][:8] == b"\x89PNG\r\n\x1a\n" and a[1][1][:5] == b"%PDF-"
    fig = draw()
    close(fig)
    assert not plt.fignum_exists(fig.number)
