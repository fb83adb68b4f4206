"""Image panels (simlunar.plotting.images): planner and point named, colour bars, the sparse-mesh
panels, sample markers covering a bounded share of the panel."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from simlunar.plotting import images


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _colorbar_labels(fig):
    return [a.get_ylabel() for a in fig.axes if a.get_label() == "<colorbar>"]


def test_image_panels_name_planner_and_point_and_have_colour_bars(rng):
    img = rng.random((20, 30))
    fig, axes = images.image_panels(
        img, img**2, (np.array([1, 2]), np.array([3, 4])), img * 2, img * 2.1,
        text=images.PanelText("k/N = 1/32", "wavelet_bn", "elevation_deg=30"),
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
    _fig, axes = images.sparse_mesh_panels(img, img, img, n_samples=7)
    assert len(axes) == 3
    assert axes[0].get_title() == "sparse mesh (7 samples),\nconstant roughness"


def test_sparse_mesh_panels_with_roughness_modulated_render_and_difference(rng):
    full = rng.random((20, 30)) + 0.5
    sparse, rough, energy = 0.9 * full, 0.7 * full, rng.random((20, 30))
    fig, axes = images.sparse_mesh_panels(sparse, full, energy, rough=rough, n_samples=9)
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
    _fig, axes = images.sparse_mesh_panels(sparse, full, rough=rough)
    assert len(axes) == 4 and axes[3].get_title() == "full resolution"
    with pytest.raises(ValueError, match="5 panels need 5 axes"):
        images.sparse_mesh_panels(sparse, full, energy, rough=rough, axes=axes)


def test_sample_markers_cover_a_bounded_share_of_the_panel(rng):
    # 25 000 samples (Table 1 at 1/64) must not paint the samples panel solid red
    img = rng.random((120, 200))
    r, c = rng.integers(0, 120, 25_000), rng.integers(0, 200, 25_000)
    _fig, axes = images.image_panels(img, img, (r, c), img, img)
    ax = axes[2]
    (sizes,) = {float(s) for s in ax.collections[0].get_sizes()}
    area_pt2 = ax.bbox.width * ax.bbox.height * (72 / ax.figure.dpi) ** 2
    assert sizes * 25_000 <= images.SAMPLE_INK * area_pt2 * 1.0001 or sizes == 0.05
    assert ax.collections[0].get_rasterized()
    # a handful of samples get big markers, capped at 4 pt²
    _fig, axes = images.image_panels(img, img, (r[:10], c[:10]), img, img)
    assert float(axes[2].collections[0].get_sizes()[0]) == 4.0
    assert not axes[2].collections[0].get_rasterized()
