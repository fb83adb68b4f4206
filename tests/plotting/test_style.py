"""The style registry: distinct colours, and one label per name in figures and tables."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import pytest
from matplotlib.colors import to_hex

from simlunar.plotting import figures as F
from simlunar.plotting import style as S
from simlunar.plotting.scanner_tables import scanner_tables
from simlunar.plotting.tables import score_tables

BASE = ("random", "grid", "gradient", "entropy", "wavelet")


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_every_registered_label_has_a_distinct_colour_and_label():
    colours = [s.colour.lower() for s in S.REGISTRY.values()]
    assert len(set(colours)) == len(colours)
    labels = [s.label for s in S.REGISTRY.values()]
    assert len(set(labels)) == len(labels)
    # spare colours for unknown names never reuse a registered colour, nor each other
    assert not set(map(str.lower, S.SPARE_COLOURS)) & set(colours)
    assert len(set(S.SPARE_COLOURS)) == len(S.SPARE_COLOURS)


def test_variants_no_longer_borrow_base_colours():
    # the quickstart's variants used to be drawn in Grid's and Gradient's colours
    base = {S.style(b).colour for b in BASE}
    for v in ("wavelet_bn", "wavelet_bn_mix", "my_new_variant", "x"):
        assert S.style(v).colour not in base


def test_unknown_names_are_deterministic_and_distinct_when_drawn_together():
    assert S.style("my_variant") == S.style("my_variant")
    assert S.label("my_variant") == "My variant"
    names = [*BASE, *(f"variant_{i}" for i in range(len(S.SPARE_COLOURS)))]
    st = S.styles(names)
    assert list(st) == names
    colours = [s.colour for s in st.values()]
    assert len(set(colours)) == len(colours)  # hash collisions resolved
    assert all(st[b] == S.REGISTRY[b] for b in BASE)  # registered names never move


def _rows(strategies):
    return [
        {"strategy": s, "density": str(d), "trial": str(t), "metric": "mse", "value": str(v)}
        for i, s in enumerate(strategies)
        for d in (0.5, 0.25)
        for t in range(2)
        for v in [(i + 1) * (1 + t) / d]
    ]


def test_figure_legend_labels_equal_table_labels():
    strategies = [*BASE, "wavelet_bn", "wavelet_bn_mix", "my_variant"]
    _fig, ax = F.error_vs_density(_rows(strategies), metric="mse", strategies=strategies)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend[-1] == F.BAND_LABEL
    scores = {"mse": {s: 1.0 for s in strategies}}
    md, _ = score_tables([("scene", scores)], strategies=strategies, metrics=["mse"])
    header = next(ln for ln in md.splitlines() if ln.startswith("| Metric"))
    table_labels = [c.strip() for c in header.strip("|").split("|")][1:]
    assert legend[:-1] == table_labels
    assert "Wavelet, blue noise" in table_labels and "wavelet_bn" not in table_labels
    # each curve is drawn in its registry colour
    for line, s in zip(ax.get_lines(), strategies):
        assert to_hex(line.get_color()) == S.styles(strategies)[s].colour
    # the ablation figure uses the same labels
    _fig, ax = F.score_vs_sweep([(1, scores), (2, scores)], strategies=strategies)
    assert [t.get_text() for t in ax.get_legend().get_texts()] == table_labels


def test_scanner_bar_labels_equal_scanner_table_labels():
    rows = [
        {"unit": "0", "mode": m, "planner": p, "budget": "0.1", "trial": str(t),
         "metric": "mse", "value": str(1.0 + t), "renders": "10"}
        for m, p in (("gray_code", ""), ("ambiguity_enhancement", "wavelet"))
        for t in range(2)
    ]  # fmt: skip
    md, _ = scanner_tables(rows, metrics=["mse"])
    table = [ln.split("|")[1].strip() for ln in md.splitlines()[4:]]
    summary = [
        {"mode": "gray_code", "planner": "", "mse": 1.5, "mse_sd": 0.7, "n": 2},
        {"mode": "ambiguity_enhancement", "planner": "wavelet", "mse": 1.5},
    ]
    _fig, ax = F.scanner_bars(summary, metric="mse")
    # the tick wraps the pair label at word boundaries and adds the count on its own line
    ticks = [" ".join(t.get_text().split("\n(n =")[0].split("\n")) for t in ax.get_xticklabels()]
    assert ticks == table == ["Gray code", "Ambiguity enhancement / Wavelet"]


def test_axis_names_and_metric_units():
    assert S.axis_name("render.light.elevation_deg") == "sun elevation (deg)"
    assert S.axis_name("render.light") == "light source"
    assert S.axis_name("study.something_else_m") == "something else (m)"
    assert S.axis_name("a.b_c") == "b c"
    assert S.metric_axis("mse") == "MSE error (m²)"
    assert S.metric_axis("rmse") == "RMSE error (m)"
    assert S.metric_axis("unknown") == "unknown error"


def test_point_titles_have_one_style_with_registry_labels_and_units():
    from simlunar.plotting.style import point_title

    assert point_title({"render.light.elevation_deg": 5}) == "sun elevation: 5°"
    light = {"kind": "sun", "elevation_deg": 30, "azimuth_deg": 135}
    assert point_title({"render.light": light}) == (
        "light source: Sun (elevation 30°, azimuth 135°)"
    )
    assert point_title({"render.light": {"kind": "camera"}}) == "light source: Camera-centred light"
    assert point_title({"terrain.albedo": None}) == "terrain albedo: preset default"
    assert point_title({"render.sensor.read_noise_e": 200}) == "sensor read noise: 200 e⁻"


def test_density_labels_are_fractions():
    from simlunar.plotting.density import density_label

    assert [density_label(d) for d in (0.5, 1 / 128, 0.15, 1 / 280)] == [
        "1/2",
        "1/128",
        "1/7",  # 1 / 0.15 = 6.67: the tables' heading, not "1/6.7"
        "1/280",
    ]
    # the ten log-spaced densities of the ablations (1/2 ... 1/512) read as their table columns
    from simlunar.config.quantities import log_spaced

    dens = log_spaced(0.5, 1 / 512, 10)
    assert [density_label(d) for d in dens] == [f"1/{round(1 / d)}" for d in dens]
    assert [density_label(d) for d in dens][:4] == ["1/2", "1/4", "1/7", "1/13"]


def test_placements_have_their_own_line_style_and_marker():
    from simlunar.plotting.style import PLACEMENT_LINES, REGISTRY

    # the same map keeps its hue family but the Lloyd layout differs in line and marker
    w, wl = REGISTRY["wavelet"], REGISTRY["wavelet_lloyd"]
    assert w.linestyle == PLACEMENT_LINES["draw"] and wl.linestyle == PLACEMENT_LINES["lloyd"]
    assert w.marker != wl.marker
    assert REGISTRY["lloyd_uniform"].marker != REGISTRY["grid"].marker
    assert REGISTRY["oracle_greedy"].linestyle == PLACEMENT_LINES["oracle"]
    assert REGISTRY["sequential_wavelet"].linestyle == PLACEMENT_LINES["sequential"]
    # the four placements are four distinct line styles, none the reference's dashes
    assert len({str(v) for v in PLACEMENT_LINES.values()}) == 4
    assert "--" not in PLACEMENT_LINES.values()


def test_a_narrow_log_axis_is_labelled_across_its_data():
    import matplotlib.pyplot as plt

    from simlunar.plotting.density import error_vs_density

    rows = [
        {"strategy": s, "density": d, "metric": "mse", "value": base * f}
        for d, base in ((0.5, 8e-5), (0.25, 1.6e-4), (0.125, 3.5e-4))
        for s, f in (("random", 1.0), ("grid", 0.7))
    ]
    fig, ax = error_vs_density(rows)
    lo, hi = ax.get_ylim()
    shown = [t for t, lab in zip(ax.get_yticks(), ax.get_yticklabels()) if lo <= t <= hi]
    labels = [
        lab.get_text() for t, lab in zip(ax.get_yticks(), ax.get_yticklabels()) if lo <= t <= hi
    ]
    # one power of ten inside the data (1e-4): 2e-4 is labelled too
    assert len(shown) >= 2 and all(labels)
    assert any(abs(t - 2e-4) < 1e-12 for t in shown)
    plt.close(fig)
