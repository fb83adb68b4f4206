"""The figures of the reconstruction axis, drawn on a tiny hand-made result folder and checked
as matplotlib objects (lines, legend entries, panels, colour scales), not as pixels: the error
curves of every planner and reconstruction, the samples each reconstruction saves over linear
(one sweep point included), the reconstruction panels, and the figures a study of one planner
must not draw (with the reason in ``not_drawn.md`` and the report)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.colors import to_hex

from simlunar.results import sampling_figures as sf
from simlunar.results.captions import Captions
from simlunar.results.figures import write_captions
from simlunar.results.report import _figures, read_captions

DENSITIES = [0.5, 0.25, 0.125, 0.0625]
N = 256  # pixels of the tiny grid (16 x 16)
#: the shading reconstruction's error is half linear's at every k, and linear's error falls as
#: 100 / k: linear needs 2k samples for shading's error at k, so shading saves exactly 2x
SHADING_FACTOR = 0.5


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _rows(unit, strategies, seed):
    out = []
    for s_i, s in enumerate(strategies):
        for d in DENSITIES:
            k = int(d * N)
            for t in range(2):
                base = (1.0 + 0.5 * s_i) * 100.0 / k * (1.0 + 0.01 * t + 0.02 * seed)
                for r, f in (("linear", 1.0), ("shading", SHADING_FACTOR)):
                    out.append({"unit": str(unit), "strategy": s, "reconstruction": r,
                                "density": str(d), "k": str(k), "trial": str(t),
                                "metric": "mse", "value": repr(f * base)})  # fmt: skip
    return out


def _folder(tmp_path, strategies=("random", "wavelet"), seeds=2, sweep_points=(30,)):
    study = {"strategies": list(strategies), "metrics": ["mse"], "terrain_seeds": seeds,
             "trials": 2, "reconstructions": ["linear", "shading"]}  # fmt: skip
    units, rows = [], []
    (tmp_path / "units").mkdir()
    rng = np.random.default_rng(0)
    r, c = np.mgrid[0:16, 0:16]
    depth = 50.0 - 0.1 * r - 0.05 * c
    for elev in sweep_points:
        for seed in range(seeds):
            i = len(units)
            planner = "wavelet" if "wavelet" in strategies else strategies[0]
            units.append({
                "index": i, "key": f"k{i}",
                "sweep": {"render.light.elevation_deg": elev, "terrain.seed_index": seed},
                "config": {"terrain": {"seed_index": seed}, "study": study,
                           "figures": {"panel_density": 1 / 16}},
                "meta": {"shape": [16, 16], "spacing_m": 0.2, "guide_frames": ["sun"],
                         "recon_panels": {"planner": planner, "density": 1 / 16, "k": 16,
                                          "reconstructions": ["linear", "shading"]}},
            })  # fmt: skip
            rows += _rows(i, strategies, seed)
            img = rng.random((16, 16))
            pr, pc = rng.choice(16, 16), rng.choice(16, 16)
            np.savez(tmp_path / "units" / f"k{i}.npz", image=img, wavelet_energy=img + 0.1,
                     plan_rows=pr, plan_cols=pc, reconstruction=depth + 0.01, depth=depth,
                     recon_panel_rows=pr, recon_panel_cols=pc,
                     recon_panel_0=depth + 0.2 * np.sin(c), recon_panel_1=depth + 0.05 * np.sin(c))  # fmt: skip
    config = {"study": study, "sweep": {"render.light.elevation_deg": list(sweep_points)}}
    return {"dir": tmp_path, "units": units, "rows": rows, "config": config}


def _draw(res):
    figs, captions = {}, Captions()
    sf.sampling_figures(res, lambda fig, stem: figs.__setitem__(stem, fig), captions)
    return figs, captions


def _legend_texts(fig):
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]
    return [t.get_text() for leg in legends for t in leg.get_texts()]


def test_error_curves_one_per_planner_and_reconstruction(tmp_path):
    figs, captions = _draw(_folder(tmp_path))
    ax = figs["error_vs_density_mse"].axes[0]
    lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == len(DENSITIES)]
    assert len(lines) == 4  # 2 planners x 2 reconstructions
    by = {ln.get_label().lstrip("_"): ln for ln in lines}
    assert set(by) == {"Random, Linear", "Random, Shading", "Wavelet, Linear", "Wavelet, Shading"}
    # colour names the planner, line style the reconstruction: each pair differs in just one
    assert to_hex(by["Random, Linear"].get_color()) == to_hex(by["Random, Shading"].get_color())
    assert to_hex(by["Random, Linear"].get_color()) != to_hex(by["Wavelet, Linear"].get_color())
    assert by["Wavelet, Linear"].get_linestyle() == by["Random, Linear"].get_linestyle()
    assert by["Wavelet, Linear"].get_linestyle() != by["Wavelet, Shading"].get_linestyle()
    # the curves are the data: shading's mean is half of linear's at every density
    np.testing.assert_allclose(
        by["Wavelet, Shading"].get_ydata(), SHADING_FACTOR * by["Wavelet, Linear"].get_ydata()
    )
    legend = _legend_texts(figs["error_vs_density_mse"])
    assert legend[:4] == ["planner: Random", "planner: Wavelet", "reconstruction: Linear",
                          "reconstruction: Shading"]  # fmt: skip
    assert len(set(legend)) == len(legend) and any(t.startswith("band:") for t in legend)
    cap = captions["error_vs_density_mse"]
    assert "Delaunay-linear; Shading" in cap and "line style the reconstruction" in cap
    assert "shaded band: ±1 standard deviation" in cap


def test_samples_saved_by_each_reconstruction_at_a_single_sweep_point(tmp_path):
    figs, captions = _draw(_folder(tmp_path))
    fig = figs["reconstruction_saved"]  # one point: no sweep axis, still drawn
    (ax,) = fig.axes  # the planners along x, a marker per reconstruction
    assert [t.get_text() for t in ax.get_xticklabels()] == ["Random", "Wavelet"]
    (line,) = [ln for ln in ax.get_lines() if ln.get_label() == "Shading"]
    # hand computation: linear's error 100/k, shading's half of it: 2x for every planner
    np.testing.assert_allclose(line.get_ydata(), [2.0, 2.0], rtol=1e-6)
    assert ax.collections, "no interval bar over the 2 terrain seeds"
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["Shading"]
    cap = captions["reconstruction_saved"]
    assert "95 % Student t interval over the seeds" in cap and "2 terrain seeds" in cap
    assert "planners along x" in cap


def test_a_one_axis_sweep_draws_against_the_swept_value(tmp_path):
    figs, _ = _draw(_folder(tmp_path, seeds=1, sweep_points=(30, 60)))
    assert "reconstruction_saved_vs_elevation_deg" in figs and "reconstruction_saved" not in figs
    ax = figs["reconstruction_saved_vs_elevation_deg"].axes[0]
    (line,) = [ln for ln in ax.get_lines() if ln.get_label() == "Shading"]
    assert len(line.get_xdata()) == 2


def test_reconstruction_panels_share_their_scales(tmp_path):
    res = _folder(tmp_path, seeds=1)
    figs, captions = _draw(res)
    fig = figs["recon_panels_unit0"]
    images = [ax for ax in fig.axes if ax.get_images()]
    assert len(images) == 6  # truth + 2 reconstructions, samples + 2 error maps
    top, bottom = images[:3], images[3:]
    assert [ax.get_title() for ax in top] == ["true depth", "Linear", "Shading"]
    assert bottom[0].get_title() == "Wavelet samples\nk/N = 1/16"
    assert bottom[1].get_title().startswith("Linear - truth\nRMS ")
    clims = {ax.get_images()[0].get_clim() for ax in top}
    assert len(clims) == 1  # one depth scale: the truth's
    err = {ax.get_images()[0].get_clim() for ax in bottom[1:]}
    assert len(err) == 1 and next(iter(err))[0] == -next(iter(err))[1]  # one symmetric scale
    # the RMS in the titles is of each map: linear's error is 4x shading's here
    rms = [float(ax.get_title().split("RMS ")[1].split()[0]) for ax in bottom[1:]]
    assert rms[0] == pytest.approx(4 * rms[1], rel=1e-2)
    assert "Wavelet planner" in captions["recon_panels_unit0"]
    assert "Delaunay-linear; Shading" in captions["recon_panels_unit0"]


def test_a_study_of_one_planner_draws_no_empty_figure_and_says_why(tmp_path):
    res = _folder(tmp_path, strategies=("lloyd_uniform",), seeds=1)
    figs, captions = _draw(res)
    assert "samples_saved" not in figs and "samples_saved" in captions.not_drawn
    assert "Uniform Lloyd" in captions.not_drawn["samples_saved"]
    assert "samples_saved_forest" not in figs
    assert "other planners: none" in captions.not_drawn["samples_saved_forest"]
    # no wavelet planner ran: no panels claim wavelet samples; the study's planner titles them
    assert "panels_unit0" not in figs and "panels_unit0" in captions.not_drawn
    assert any("Uniform Lloyd samples" in ax.get_title() for ax in figs["recon_panels_unit0"].axes)
    # the error figure: one planner, two reconstructions, two curves
    ax = figs["error_vs_density_mse"].axes[0]
    assert len([ln for ln in ax.get_lines() if len(ln.get_xdata()) == len(DENSITIES)]) == 2
    assert "reconstruction_saved" in figs
    for stem, fig in figs.items():  # nothing drawn is empty
        assert any(ax.get_lines() or ax.get_images() or ax.patches for ax in fig.axes), stem
    # the reasons reach figures/not_drawn.md and the report
    fig_dir = tmp_path / "figures"
    fig_dir.mkdir()
    written = []
    write_captions(fig_dir, captions, written)
    assert {p.name for p in written} == {"captions.md", "not_drawn.md"}
    assert read_captions(fig_dir, "not_drawn.md") == captions.not_drawn
    page = _figures(fig_dir)
    assert "Not drawn" in page and "<code>samples_saved</code>" in page


def test_linear_alone_draws_no_reconstruction_comparison(tmp_path):
    res = _folder(tmp_path, seeds=1)
    res["config"]["study"]["reconstructions"] = ["linear"]
    res["rows"] = [r for r in res["rows"] if r["reconstruction"] == "linear"]
    figs, captions = _draw(res)
    assert not any(s.startswith("reconstruction_saved") for s in figs)
    assert "one reconstruction" in captions.not_drawn["reconstruction_saved"]
    assert "recon_panels_unit0" not in figs  # panels_unit0 shows the one reconstruction
    ax = figs["error_vs_density_mse"].axes[0]
    assert len([ln for ln in ax.get_lines() if len(ln.get_xdata()) == len(DENSITIES)]) == 2


def test_a_shared_legend_of_several_panels_names_planners_and_reconstructions_once(tmp_path):
    figs, _ = _draw(_folder(tmp_path, seeds=1, sweep_points=(30, 60)))
    fig = figs["error_vs_density_mse"]
    assert len([ax for ax in fig.axes if ax.get_lines()]) == 2
    texts = _legend_texts(fig)
    # not one entry per curve ("Random, Linear", ...): one per planner and per reconstruction
    assert [t for t in texts if not t.startswith("band")] == [
        "planner: Random", "planner: Wavelet", "reconstruction: Linear", "reconstruction: Shading"]  # fmt: skip
