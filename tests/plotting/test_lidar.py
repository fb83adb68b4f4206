"""The waveform figure draws counts, expectation and returns."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.plotting.lidar import waveform


def test_waveform_draws_every_element(tmp_path):
    r = np.linspace(45.0, 55.0, 200)
    lam = (
        0.5
        + 20 * np.exp(-0.5 * ((r - 49.0) / 0.1) ** 2)
        + 30 * np.exp(-0.5 * ((r - 50) / 0.1) ** 2)
    )
    counts = np.random.default_rng(0).poisson(lam)
    fig, ax = waveform(
        r,
        counts,
        expected=lam,
        returns={"first": 49.0, "last": 50.0},
        truth={"rock": 49.0},
        title="edge",
    )
    assert len(ax.lines) == 1 + 1 + 2 + 1  # step, expected, two returns, truth
    assert ax.get_title() == "edge"
    fig.savefig(tmp_path / "w.png")
    assert (tmp_path / "w.png").stat().st_size > 1000


def _rows():
    """Two planners, two k, two units (terrain seeds), two trials; CSV-like strings."""
    rows = []
    for unit in (0, 1):
        for planner, scale in (("grid", 1.0), ("wavelet", 2.0)):
            for k, secs in ((64, 4.0), (256, 12.0)):
                for trial in (0, 1):
                    v = scale / k * (1 + unit) * (1 + 0.1 * trial)
                    rows.append({"unit": str(unit), "planner": planner, "k": str(k),
                                 "trial": str(trial), "metric": "mse", "value": str(v),
                                 "seconds": str(secs * scale)})  # fmt: skip
    return rows


def test_error_vs_time_draws_a_curve_per_planner(tmp_path):
    from simlunar.plotting.lidar import error_vs_time

    fig, ax = error_vs_time(_rows(), metric="mse", planners=["wavelet", "grid", "absent"])
    assert [c.get_label() for c in ax.containers] == ["Wavelet", "Grid"]
    assert ax.containers[1].lines[0].get_xdata().tolist() == [4.0, 12.0]
    assert ax.get_xlabel() == "scan time (s)"
    _, ax = error_vs_time(_rows(), metric="mse", x="samples")  # rows without it: k
    assert ax.get_xlabel() == "range samples measured"
    assert ax.containers[0].lines[0].get_xdata().tolist() == [64, 256]
    fig.savefig(tmp_path / "t.png")


def _beams(n, rng):
    rc = rng.uniform(0, 31, size=(n, 2))
    depth = 20.0 + rc[:, 0] / 31
    depth[::7] = np.nan  # no return: 8 of 50, 10 of 64 (84 % returned)
    return np.c_[rc, np.linspace(0, 1, n), depth]


def test_scan_figure_draws_the_tour_and_the_measured_depths(tmp_path):
    from matplotlib.collections import LineCollection

    from simlunar.plotting.lidar import MAX_SCAN_PLANNERS, scan_figure

    rng = np.random.default_rng(0)
    image = rng.uniform(size=(32, 32))
    depth = 20.0 + np.repeat(np.arange(32.0)[:, None], 32, axis=1) / 31
    beams = {"wavelet": _beams(50, rng), "grid": _beams(64, rng)}
    fig = scan_figure(image, depth, beams, title="exp: steered beam scan")
    assert fig._suptitle.get_text() == "exp: steered beam scan"
    titles = [ax.get_title() for ax in fig.axes]
    assert titles[:6] == ["guide image", "Wavelet: 50 beams", "Grid: 64 beams",
                          "true z-depth", "84 % returned",
                          "84 % returned"]  # fmt: skip
    # the tour: one segment between consecutive beams, coloured by their share of the scan
    tour = next(c for c in fig.axes[1].collections if isinstance(c, LineCollection))
    assert len(tour.get_segments()) == 49
    np.testing.assert_allclose(tour.get_array()[[0, -1]], [0.0, 48 / 49])
    np.testing.assert_array_equal(tour.get_segments()[0], beams["wavelet"][:2, [1, 0]])
    # two colour bars: visiting order and depth
    assert {ax.get_ylabel() for ax in fig.axes[6:]} == {
        "visiting order\n(share of the scan)",
        "z-depth (m)",
    }
    fig.savefig(tmp_path / "scan.png")
    many = {f"p{i}": _beams(10, rng) for i in range(MAX_SCAN_PLANNERS + 2)}
    fig = scan_figure(image, depth, many)
    assert sum(ax.get_title().endswith("beams") for ax in fig.axes) == MAX_SCAN_PLANNERS
    with pytest.raises(ValueError, match="at least one planner"):
        scan_figure(image, depth, {})


def test_an_oracle_curve_is_dotted_as_a_bound():
    from simlunar.plotting.lidar import error_vs_time

    rows = [{**r, "planner": "oracle_greedy"} for r in _rows() if r["planner"] == "grid"]
    _, ax = error_vs_time(_rows() + rows, metric="mse", planners=["grid", "oracle_greedy"])
    lines = {c.get_label(): c.lines[0] for c in ax.containers}
    assert lines["Oracle greedy (true error)"].get_linestyle() == ":"
    assert lines["Grid"].get_linestyle() == "-"


def test_scan_figure_titles_do_not_overlap():
    """Long planner labels (an oracle's) in narrow panels: the titles are wrapped to their
    panel, so no two titles of a row share a pixel (they ran into each other)."""
    from simlunar.plotting.lidar import MAX_SCAN_PLANNERS, scan_figure

    rng = np.random.default_rng(1)
    image = rng.uniform(size=(32, 48))
    depth = 20.0 + rng.uniform(size=(32, 48))
    names = ["oracle_greedy", "oracle_hessian", "sequential_wavelet", "wavelet_lloyd", "grid"]
    beams = {n: _beams(40, rng) for n in names[:MAX_SCAN_PLANNERS]}
    fig = scan_figure(image, depth, beams)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)  # a Figure made without pyplot has no renderer of its own
    canvas.draw()
    renderer = canvas.get_renderer()
    boxes = [ax.title.get_window_extent(renderer) for ax in fig.axes if ax.get_title()]
    assert len(boxes) >= 2 * (1 + len(beams)) - 1
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert not a.overlaps(b), (a, b)


def test_error_vs_time_draws_every_reconstruction_of_a_planner():
    """Rows of two reconstructions (linear's without the column, as older rows are written):
    a curve per planner and reconstruction, colour by planner, line style by reconstruction,
    a legend entry for each planner and each reconstruction."""
    from matplotlib.colors import to_hex

    from simlunar.plotting.lidar import error_vs_time

    rows = _rows() + [{**r, "reconstruction": "shading", "value": str(0.5 * float(r["value"]))}
                      for r in _rows()]  # fmt: skip
    _fig, ax = error_vs_time(rows, metric="mse", planners=["grid", "wavelet"],
                            reconstructions=["linear", "shading"])  # fmt: skip
    curves = {c.get_label(): c.lines[0] for c in ax.containers}
    assert list(curves) == ["Grid, Linear", "Wavelet, Linear", "Grid, Shading", "Wavelet, Shading"]
    np.testing.assert_allclose(
        curves["Grid, Shading"].get_ydata(), 0.5 * curves["Grid, Linear"].get_ydata()
    )
    c = {k: to_hex(v.get_color()) for k, v in curves.items()}
    assert c["Grid, Linear"] == c["Grid, Shading"] != c["Wavelet, Linear"]
    ls = {k: v.get_linestyle() for k, v in curves.items()}
    assert ls["Grid, Linear"] == ls["Wavelet, Linear"] != ls["Grid, Shading"]
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert texts == ["planner: Grid", "planner: Wavelet", "reconstruction: Linear",
                     "reconstruction: Shading"]  # fmt: skip
