"""Figures: data reach the axes (means over trials, positions), ax= composes, files save."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
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


def test_mean_error_by_density_is_the_trial_mean():
    d, m, sd = F.mean_error_by_density(rows(), metric="mse", strategy="wavelet")
    assert d.tolist() == [0.5, 0.25, 0.125]
    np.testing.assert_allclose(m, [2.0, 4.0, 8.0])  # mean of 0.9x and 1.1x
    np.testing.assert_allclose(sd, np.array([2.0, 4.0, 8.0]) * np.std([0.9, 1.1], ddof=1))
    d, m, _ = F.mean_error_by_density(rows(), metric="mse", strategy="wavelet", where={"unit": 1})
    assert d.size == 0


def test_error_vs_density_plots_each_strategy_on_log_axes():
    _fig, ax = F.error_vs_density(rows(), metric="mse")
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    assert set(lines) == {"Random", "Wavelet"}
    np.testing.assert_allclose(lines["Random"].get_ydata(), [4.0, 8.0, 16.0])
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    assert ax.xaxis_inverted()


def test_ax_argument_draws_into_the_given_axes():
    fig, axes = plt.subplots(1, 2)
    f2, a2 = F.error_vs_density(rows(), metric="mse", ax=axes[1])
    assert f2 is fig and a2 is axes[1]
    _f3, a3 = F.score_vs_sweep(
        [(5, {"mse": {"wavelet": 1.2}}), (30, {"mse": {"wavelet": 1.4}})],
        ax=axes[0],
        axis_label="elevation",
    )
    assert a3 is axes[0]
    (line,) = [ln for ln in a3.get_lines() if ln.get_label() == "Wavelet"]
    assert line.get_xdata().tolist() == [5.0, 30.0]
    assert line.get_ydata().tolist() == [1.2, 1.4]


def test_score_vs_sweep_with_labels_draws_categories_unconnected():
    _fig, ax = F.score_vs_sweep(
        [
            ("lambert", {"mse": {"grid": 0.9, "wavelet": 1.0}}),
            ("oren_nayar", {"mse": {"grid": 1.1}}),
        ]
    )
    assert [t.get_text() for t in ax.get_xticklabels()] == ["Lambert", "Oren-Nayar"]
    grid = next(ln for ln in ax.get_lines() if ln.get_label() == "Grid")
    assert grid.get_linestyle() == "None"  # no line between two categories
    assert grid.get_ydata().tolist() == [0.9, 1.1]
    # side by side: each strategy's markers sit off the category centre, in opposite ways
    wav = next(ln for ln in ax.get_lines() if ln.get_label() == "Wavelet")
    assert grid.get_xdata()[0] < 0 < wav.get_xdata()[0]
    assert ax.get_ylabel() == "MSE score (random = 1)"


def test_numeric_sweep_draws_lines():
    _fig, ax = F.score_vs_sweep([(5, {"mse": {"grid": 1}}), (30, {"mse": {"grid": 2}})])
    (line,) = [ln for ln in ax.get_lines() if ln.get_label() == "Grid"]
    assert line.get_linestyle() == "-"


def test_error_axes_have_units_and_the_band_is_explained():
    _fig, ax = F.error_vs_density(rows(), metric="mse")
    assert ax.get_ylabel() == "MSE error (m²)"
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["Random", "Wavelet", F.BAND_LABEL]
    # no spread (one trial): no band, so no band entry
    one = [r for r in rows() if r["trial"] == "0"]
    _fig, ax = F.error_vs_density(one, metric="mse")
    assert F.BAND_LABEL not in [t.get_text() for t in ax.get_legend().get_texts()]


def _colorbar_labels(fig):
    return [a.get_ylabel() for a in fig.axes if a.get_label() == "<colorbar>"]


def test_image_panels_name_planner_and_point_and_have_colour_bars(rng):
    img = rng.random((20, 30))
    fig, axes = F.image_panels(
        img, img**2, (np.array([1, 2]), np.array([3, 4])), img * 2, img * 2.1,
        text=F.PanelText("k/N = 1/32", "wavelet_bn", "elevation_deg=30"),
    )  # fmt: skip
    assert len(axes) == 6
    assert axes[2].get_title() == "Wavelet, blue noise samples, k/N = 1/32"
    assert fig._suptitle.get_text() == "elevation_deg=30"
    offsets = axes[2].collections[0].get_offsets()
    np.testing.assert_array_equal(np.asarray(offsets), [[3, 1], [4, 2]])  # (x=col, y=row)
    err = axes[5].images[0].get_array()
    np.testing.assert_allclose(err, img * 2 - img * 2.1)
    # truth and reconstruction share one colour scale
    assert axes[3].images[0].get_clim() == axes[4].images[0].get_clim()
    assert _colorbar_labels(fig) == ["sensor value (0-1)", "log10 energy", "depth (m)", "error (m)"]


def test_sparse_mesh_panels(rng):
    img = rng.random((20, 30))
    _fig, axes = F.sparse_mesh_panels(img, img, img, n_samples=7)
    assert len(axes) == 3
    assert axes[0].get_title() == "sparse mesh (7 samples),\nconstant roughness"


def test_sparse_mesh_panels_with_roughness_modulated_render_and_difference(rng):
    full = rng.random((20, 30)) + 0.5
    sparse, rough, energy = 0.9 * full, 0.7 * full, rng.random((20, 30))
    fig, axes = F.sparse_mesh_panels(sparse, full, energy, rough=rough, n_samples=9)
    top = np.percentile(full, 99.5)
    # the difference's scale: the 99th percentile of |difference| (not a few extreme pixels)
    lim = np.percentile(np.abs(rough - sparse) / top, 99)
    titles = [a.get_title() for a in axes]
    assert titles == [
        "sparse mesh (9 samples),\nroughness from energy",
        "energy - constant roughness",
        "sparse mesh (9 samples),\nconstant roughness",
        "full resolution",
        "frequency map",
    ]
    # one exposure for the three renders: the 99.5th percentile of the full render
    np.testing.assert_allclose(axes[0].images[0].get_array(), np.clip(rough / top, 0, 1))
    np.testing.assert_allclose(axes[2].images[0].get_array(), np.clip(sparse / top, 0, 1))
    # the difference panel: (rough - sparse) / exposure on a symmetric scale
    np.testing.assert_allclose(axes[1].images[0].get_array(), (rough - sparse) / top)
    assert axes[1].images[0].get_clim() == pytest.approx((-lim, lim))
    # log scale floored at the 1st percentile of the positive energies
    logged = np.log10(np.maximum(energy, np.percentile(energy, 1)))
    np.testing.assert_allclose(axes[4].images[0].get_array(), logged, rtol=1e-12)
    assert "log10 wavelet energy" in _colorbar_labels(fig)
    # without the frequency map: four panels
    _fig, axes = F.sparse_mesh_panels(sparse, full, rough=rough)
    assert len(axes) == 4 and axes[3].get_title() == "full resolution"
    with pytest.raises(ValueError, match="5 panels need 5 axes"):
        F.sparse_mesh_panels(sparse, full, energy, rough=rough, axes=axes)


def test_scanner_bars_draw_error_bars():
    summary = [
        {"mode": "gray_code", "planner": "", "mse": 2.0, "mse_sd": 0.5, "n": 6},
        {"mode": "ambiguity_enhancement", "planner": "wavelet", "mse": 1.5, "mse_sd": 0.25},
    ]
    _fig, ax = F.scanner_bars(summary, metric="mse")
    bars = next(c for c in ax.containers if hasattr(c, "errorbar"))
    assert bars.errorbar is not None
    segs = bars.errorbar.lines[2][0].get_segments()
    np.testing.assert_allclose([s[:, 1] for s in segs], [[1.5, 2.5], [1.25, 1.75]])
    assert ax.get_xticklabels()[0].get_text() == "Gray code\n(n = 6)"
    assert ax.get_ylabel() == "MSE error (m²)"


def test_bit_error_plot_with_no_errors_says_so():
    _fig, ax = F.bit_error_rates({"ber_c0": 0.0, "ber_c1": 0.0, "ber_r0": 0.0})
    texts = [t.get_text() for t in ax.texts]
    assert texts == ["no bit errors: all 3 per-bit rates are 0"]
    _fig, ax = F.bit_error_rates({"ber_c0": 0.02, "ber_c1": 0.0})
    assert len(ax.texts) == 0 and ax.get_ylim()[0] == 0.0
    assert ax.get_ylabel() == "bit errors per 100 pixels"
    assert list(ax.lines[0].get_ydata()) == pytest.approx([2.0, 0.0])


def test_small_bit_error_rates_get_a_unit_not_an_offset():
    # 1.66e-7 on a fraction axis printed "1e-7" above the axis (the DLP run's figure)
    fig, ax = F.bit_error_rates({"ber_c7": 0.0, "ber_c8": 1.66e-7, "ber_r8": 0.0})
    assert ax.get_ylabel() == "bit errors per billion pixels"
    assert max(ax.lines[0].get_ydata()) == pytest.approx(166.0)
    fig.canvas.draw()
    assert ax.yaxis.get_offset_text().get_text() == ""


def test_save_is_deterministic():
    a = dict(F.save(F.error_vs_density(rows(), metric="mse")[0], "x", ("png", "pdf")))
    b = dict(F.save(F.error_vs_density(rows(), metric="mse")[0], "x", ("png", "pdf")))
    assert a["png"][:8] == b"\x89PNG\r\n\x1a\n" and a["pdf"][:5] == b"%PDF-"
    assert a == b


def test_where_with_a_list_pools_units():
    # unit 1: the same design at 3x the error; pooling both units averages four values
    both = rows() + [dict(r, unit="1", value=str(3 * float(r["value"]))) for r in rows()]
    d, m, sd = F.mean_error_by_density(
        both, metric="mse", strategy="wavelet", where={"unit": [0, 1]}
    )
    assert d.tolist() == [0.5, 0.25, 0.125]
    vals = np.array([0.9, 1.1, 2.7, 3.3])  # x (1/d) for trials 0, 1 of units 0 and 1
    np.testing.assert_allclose(m, np.array([2.0, 4.0, 8.0]) * vals.mean())
    np.testing.assert_allclose(sd, np.array([2.0, 4.0, 8.0]) * vals.std(ddof=1))
    _d, m1, _ = F.mean_error_by_density(
        both, metric="mse", strategy="wavelet", where={"unit": (1,)}
    )
    np.testing.assert_allclose(m1, [6.0, 12.0, 24.0])


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


def test_sample_markers_cover_a_bounded_share_of_the_panel(rng):
    # 25 000 samples (Table 1 at 1/64) must not paint the samples panel solid red
    img = rng.random((120, 200))
    r, c = rng.integers(0, 120, 25_000), rng.integers(0, 200, 25_000)
    _fig, axes = F.image_panels(img, img, (r, c), img, img)
    ax = axes[2]
    (sizes,) = {float(s) for s in ax.collections[0].get_sizes()}
    area_pt2 = ax.bbox.width * ax.bbox.height * (72 / ax.figure.dpi) ** 2
    assert sizes * 25_000 <= F.SAMPLE_INK * area_pt2 * 1.0001 or sizes == 0.05
    assert ax.collections[0].get_rasterized()
    # a handful of samples get big markers, capped at 4 pt²
    _fig, axes = F.image_panels(img, img, (r[:10], c[:10]), img, img)
    assert float(axes[2].collections[0].get_sizes()[0]) == 4.0
    assert not axes[2].collections[0].get_rasterized()


def _scan_summary(mse_gray, mse_dots, valid):
    return [
        {"mode": "gray_code", "planner": "", "mse": mse_gray, "valid_fraction": valid},
        {"mode": "ambiguity_enhancement", "planner": "wavelet", "mse": mse_dots,
         "mse_sd": mse_dots / 10, "valid_fraction": valid},
    ]  # fmt: skip


def test_scanner_vs_sweep_draws_each_pair_against_the_axis():
    pts = [(0.3, _scan_summary(1e-6, 9e-7, 1.0)), (30, _scan_summary(3e-6, 2e-5, 0.9)),
           (100, _scan_summary(2e-3, 3e-3, 0.01))]  # fmt: skip
    _fig, ax = F.scanner_vs_sweep(pts, metric="mse", axis_label="sun", secondary=(0.24, "ratio"))
    lines = {c.get_label(): c.lines[0] for c in ax.containers}  # errorbar containers
    assert set(lines) == {"Gray code", "Ambiguity enhancement / Wavelet"}
    np.testing.assert_allclose(lines["Gray code"].get_ydata(), [1e-6, 3e-6, 2e-3])
    np.testing.assert_allclose(lines["Gray code"].get_xdata(), [0.3, 30, 100])
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"  # both span > 20x
    (top,) = [c for c in ax.child_axes]
    assert top.get_xlabel() == "ratio"
    _fig, ax = F.scanner_vs_sweep(pts, metric="valid_fraction")
    assert ax.get_yscale() == "linear" and ax.get_ylabel() == "valid fraction of guide pixels"
    assert ax.get_ylim() == pytest.approx((-0.02, 1.02))
    # all close to 1: the axis zooms in so 0.994 vs 1.0 is visible
    near = [(x, _scan_summary(1e-6, 1e-6, v)) for x, v in ((1, 1.0), (2, 0.994))]
    _fig, ax = F.scanner_vs_sweep(near, metric="valid_fraction")
    lo, hi = ax.get_ylim()
    assert 0.99 < lo < 0.994 and 1.0 < hi < 1.002
    # categories: unconnected markers at 0, 1, 2
    _fig, ax = F.scanner_vs_sweep([("a", p[1]) for p in pts], metric="mse")
    (gray,) = [c.lines[0] for c in ax.containers if c.get_label() == "Gray code"]
    assert gray.get_linestyle() == "None" and gray.get_xdata().tolist() == [0, 1, 2]


def test_shared_legend_keeps_labels_of_panels_with_different_quantities():
    fig, axes = F.panel_grid(2)
    F.error_vs_density(rows(), metric="mse", ax=axes[0])
    F.error_vs_density(rows(), metric="mse", ax=axes[1])
    axes[1].set_ylabel("GRAD error (m²)")
    F.shared_legend(fig, axes, prune_labels=False)
    assert [a.get_ylabel() for a in axes] == ["MSE error (m²)", "GRAD error (m²)"]
