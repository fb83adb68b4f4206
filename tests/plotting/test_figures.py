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


def test_score_vs_sweep_with_labels():
    _fig, ax = F.score_vs_sweep(
        [("lambert", {"mse": {"grid": 0.9}}), ("hapke", {"mse": {"grid": 1.1}})]
    )
    assert [t.get_text() for t in ax.get_xticklabels()] == ["lambert", "hapke"]


def test_image_panels_and_sparse_mesh(rng):
    img = rng.random((20, 30))
    _fig, axes = F.image_panels(img, img**2, np.array([1, 2]), np.array([3, 4]), img * 2, img * 2.1)
    assert len(axes) == 5
    offsets = axes[2].collections[0].get_offsets()
    np.testing.assert_array_equal(np.asarray(offsets), [[3, 1], [4, 2]])  # (x=col, y=row)
    err = axes[4].images[0].get_array()
    np.testing.assert_allclose(err, img * 2 - img * 2.1)
    _fig, axes = F.sparse_mesh_panels(img, img, img, n_samples=7)
    assert len(axes) == 3
    assert axes[0].get_title() == "sparse mesh (7 samples),\nconstant roughness"


def test_sparse_mesh_panels_with_roughness_modulated_render(rng):
    full = rng.random((20, 30)) + 0.5
    sparse, rough, energy = 0.9 * full, 0.7 * full, rng.random((20, 30))
    _fig, axes = F.sparse_mesh_panels(sparse, full, energy, rough=rough, n_samples=9)
    titles = [a.get_title() for a in axes]
    assert titles == [
        "sparse mesh (9 samples),\nroughness from energy",
        "sparse mesh (9 samples),\nconstant roughness",
        "full resolution",
        "frequency map",
    ]
    # one exposure for the three renders: the 99.5th percentile of the full render
    top = np.percentile(full, 99.5)
    np.testing.assert_allclose(axes[0].images[0].get_array(), np.clip(rough / top, 0, 1))
    np.testing.assert_allclose(axes[1].images[0].get_array(), np.clip(sparse / top, 0, 1))
    # log scale floored at the 1st percentile of the positive energies
    logged = np.log10(np.maximum(energy, np.percentile(energy, 1)))
    np.testing.assert_allclose(axes[3].images[0].get_array(), logged, rtol=1e-12)
    # without the frequency map: three panels
    _fig, axes = F.sparse_mesh_panels(sparse, full, rough=rough)
    assert len(axes) == 3 and axes[2].get_title() == "full resolution"
    with pytest.raises(ValueError, match="4 panels need 4 axes"):
        F.sparse_mesh_panels(sparse, full, energy, rough=rough, axes=axes)


def test_save_is_deterministic():
    a = dict(F.save(F.error_vs_density(rows(), metric="mse")[0], "x", ("png", "pdf")))
    b = dict(F.save(F.error_vs_density(rows(), metric="mse")[0], "x", ("png", "pdf")))
    assert a["png"][:8] == b"\x89PNG\r\n\x1a\n" and a["pdf"][:5] == b"%PDF-"
    assert a == b
