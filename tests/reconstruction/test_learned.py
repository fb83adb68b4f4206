"""The learned residual reconstruction: features, anchoring, a planted relation on held-out
terrains, model files (checked before unpickling), determinism, the registry entry."""

from __future__ import annotations

import json

import joblib
import numpy as np
import pytest
from scipy import ndimage

from simlunar.features.learned import LearnedMap, LearnedOptions
from simlunar.planner.learning import train_learned_map, train_learned_reconstruction
from simlunar.planner.sequential import uniform_layout
from simlunar.reconstruction import RECONSTRUCTIONS, Guide, reconstruct, run_reconstruction
from simlunar.reconstruction import learned as lr
from simlunar.reconstruction.learned import (
    FORMAT,
    LearnedReconOptions,
    LearnedReconstruction,
    anchor,
    feature_names,
    residual_features,
    sample_scale,
)
from simlunar.registry import Entry

DENSITIES = (1 / 32, 1 / 16)
#: held-out MSE of linear over MSE of the learned reconstruction the model must reach on every
#: test terrain and density; measured 11-34x on seeds 100-102 at 1/48, 1/32, 1/16 (96 x 128
#: cells, 4 training terrains, 60 rounds); a model predicting zeros gives exactly 1
MIN_GAIN = 5.0
FAST = LearnedOptions(layouts=2, pixels_per_example=2000, max_iter=40)


def planted_pair(seed: int, shape=(64, 96)):
    """A planted image-height relation: fine relief d the samples miss, shown by the image.

    truth = smooth base (what linear interpolation recovers) + amp d, d a unit-variance
    Gaussian-smoothed (sigma 1.5 cells) noise; the image is 0.5 + 0.15 d plus 1 % noise (an
    albedo that follows the fine relief), so the residual truth - linear is a function of the
    image (up to the anchoring). amp varies from terrain to terrain in [0.5, 2]: the model
    must scale its residual by the samples' own roughness.
    """
    r = np.random.default_rng(seed)
    base = ndimage.gaussian_filter(r.standard_normal(shape), 16) * 40
    d = ndimage.gaussian_filter(r.standard_normal(shape), 1.5)
    d /= d.std()
    truth = base + r.uniform(0.5, 2.0) * d
    image = np.clip(0.5 + 0.15 * d + 0.01 * r.standard_normal(shape), 0.01, None)
    return image, truth


def layout(truth, density, seed):
    r, c = np.divmod(
        uniform_layout(truth.shape, round(density * truth.size), rng=seed), truth.shape[1]
    )
    return np.column_stack((r, c)), truth[r, c]


def gains(recon, pairs, density) -> list[float]:
    """MSE(linear) / MSE(recon) on each held-out pair (same uniform Lloyd layout)."""
    out = []
    for i, (img, z) in enumerate(pairs):
        pts, vals = layout(z, density, 50 + i)
        lin = reconstruct(pts, vals, z.shape)
        out.append(np.mean((lin - z) ** 2) / np.mean((recon(img, pts, vals) - z) ** 2))
    return out


@pytest.fixture(scope="module")
def model():
    return train_learned_reconstruction(
        [planted_pair(s) for s in range(4)], densities=DENSITIES, options=FAST, rng=0
    )


@pytest.fixture(scope="module")
def held_out():
    return [planted_pair(s) for s in range(100, 103)]


def _recon(m, check=False):
    """The model's reconstruction, without the held-out check unless ``check``."""
    return lambda img, pts, vals: (
        m.reconstruct(pts, vals, img.shape, guide=Guide(img), heldout_check=check).heights
    )


def test_feature_stack_names_shapes_and_scale():
    img, z = planted_pair(0, shape=(40, 50))
    pts, vals = layout(z, 1 / 16, 0)
    x, h, z_lin = residual_features(img, pts, vals)
    assert x.shape == (40 * 50, len(feature_names())) and x.dtype == np.float32
    assert np.isfinite(x).all() and len(set(feature_names())) == len(feature_names())
    np.testing.assert_array_equal(z_lin, reconstruct(pts, vals, z.shape))
    shade = z_lin + 1.0
    xs, _, _ = residual_features(img, pts, vals, shading=shade)
    assert xs.shape[1] == len(feature_names(True)) == x.shape[1] + 1
    np.testing.assert_allclose(xs[:, -1], 1.0 / h, rtol=1e-6)  # (shading - linear) / h
    # distance to the nearest sample is 0 on the samples, in pitches elsewhere
    dist = x[:, feature_names().index("dist_pitch")].reshape(z.shape)
    assert np.all(dist[pts[:, 0], pts[:, 1]] == 0) and dist.max() > 0.3
    dens = x[:, feature_names().index("log2_density")]
    np.testing.assert_allclose(dens, np.log2(len(pts) / z.size), rtol=1e-6)


def test_sample_scale_ignores_planes_and_scales_with_relief():
    rng = np.random.default_rng(3)
    pts = np.unique(rng.integers(0, 50, size=(200, 2)), axis=0).astype(float)
    plane = 2.0 + 0.3 * pts[:, 0] - 0.7 * pts[:, 1]
    h0, loo = sample_scale(pts, plane)
    assert h0 == pytest.approx(0.0, abs=1e-9) and len(loo) == len(pts)
    bumps = rng.normal(size=len(pts))
    h1, _ = sample_scale(pts, bumps)
    # the leave-one-out residual against a neighbours' plane is linear in the values and blind
    # to an added plane
    assert sample_scale(pts, 5 * bumps)[0] == pytest.approx(5 * h1)
    assert sample_scale(pts, bumps + plane)[0] == pytest.approx(h1)


def test_anchoring_keeps_measured_cells():
    rng = np.random.default_rng(4)
    _, z = planted_pair(1, shape=(30, 40))
    pts, vals = layout(z, 1 / 8, 1)
    z_lin = reconstruct(pts, vals, z.shape)
    r = rng.normal(size=z.shape)
    out = anchor(z_lin, r, pts)
    np.testing.assert_allclose(out[pts[:, 0], pts[:, 1]], vals, atol=1e-12)
    assert np.abs(out - z_lin).max() > 0.5  # and changes the cells between them


def test_learned_residual_recovers_planted_relation_on_held_out_terrains(model, held_out):
    # trained densities and one between / beyond them (density is a feature)
    for d in (*DENSITIES, 1 / 48):
        g = gains(_recon(model), held_out, d)
        assert min(g) >= MIN_GAIN, (d, g)


def test_criterion_fails_a_model_that_predicts_zeros(model, held_out):
    class Zeros:
        def predict(self, x):
            return np.zeros(len(x))

    zero = LearnedReconstruction(Zeros(), model.meta)
    g = gains(_recon(zero), held_out, DENSITIES[0])
    np.testing.assert_allclose(g, 1.0)  # exactly linear
    assert min(g) < MIN_GAIN


def test_measured_cells_keep_their_values(model, held_out):
    img, z = held_out[0]
    pts, vals = layout(z, 1 / 32, 7)
    out = model.reconstruct(pts, vals, z.shape, guide=Guide(img))
    np.testing.assert_allclose(out.heights[pts[:, 0], pts[:, 1]], vals, atol=1e-9)
    assert out.info["scale_m"] > 0 and out.info["residual_rms_m"] > 0


def test_samples_on_a_plane_give_linear():
    img, _ = planted_pair(2, shape=(30, 40))
    r, c = np.mgrid[0:30:3, 0:40:3]
    pts = np.column_stack((r.ravel(), c.ravel()))
    vals = 1.0 + 0.1 * pts[:, 0] + 0.2 * pts[:, 1]

    class Boom:
        def predict(self, x):
            raise AssertionError("no residual to scale: the model is not asked")

    out = LearnedReconstruction(Boom(), {}).reconstruct(pts, vals, (30, 40), guide=Guide(img))
    np.testing.assert_allclose(out.heights, reconstruct(pts, vals, (30, 40)))
    assert out.info["residual_rms_m"] == 0.0


def test_save_load_round_trip_and_record(model, held_out, tmp_path):
    path, record = model.save(tmp_path / "sub" / "r.joblib")
    assert record == tmp_path / "sub" / "r.json"
    meta = json.loads(record.read_text())
    assert meta["format"] == FORMAT and meta["feature_names"] == list(feature_names())
    assert meta["densities"] == sorted(DENSITIES) and meta["examples"] == 4
    assert meta["options"]["max_iter"] == 40 and len(meta["input_sha256"]) == 4
    assert meta["with_shading"] is False and {"scikit-learn", "numpy"} <= set(meta["versions"])
    loaded = LearnedReconstruction.load(path)
    img, z = held_out[1]
    pts, vals = layout(z, 1 / 32, 3)
    a = model.reconstruct(pts, vals, z.shape, guide=Guide(img))
    b = loaded.reconstruct(pts, vals, z.shape, guide=Guide(img))
    np.testing.assert_array_equal(a.heights, b.heights)


def test_training_is_deterministic(tmp_path):
    pairs = [planted_pair(s, shape=(40, 48)) for s in range(2)]
    opts = LearnedOptions(layouts=1, pixels_per_example=800, max_iter=15)
    hashes = set()
    for i in range(2):
        m = train_learned_reconstruction(pairs, densities=[1 / 16], options=opts, rng=7)
        m.save(tmp_path / f"m{i}.joblib")
        hashes.add(json.loads((tmp_path / f"m{i}.json").read_text())["model_sha256"])
    assert len(hashes) == 1
    m = train_learned_reconstruction(pairs, densities=[1 / 16], options=opts, rng=8)
    m.save(tmp_path / "other.joblib")
    assert json.loads((tmp_path / "other.json").read_text())["model_sha256"] not in hashes


@pytest.fixture
def no_unpickling(monkeypatch):
    """Fail the test if anything is unpickled."""

    def boom(*a, **k):
        raise AssertionError("unpickled a refused file")

    monkeypatch.setattr(joblib, "load", boom)


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        ("truncate", "SHA-256"),
        ("tamper", "SHA-256"),
        ("format", "not a simlunar-learned-reconstruction/1"),
        ("features", "another feature set"),
        ("sklearn_version", "scikit-learn"),
        ("bad_json", "not a readable JSON record"),
        ("no_record", "needs both"),
    ],
)
def test_load_refuses_bad_files_before_unpickling(model, tmp_path, edit, match, no_unpickling):
    path, record = model.save(tmp_path / "m.joblib")
    meta = json.loads(record.read_text())
    data = path.read_bytes()
    if edit == "truncate":
        path.write_bytes(data[: len(data) // 2])
    elif edit == "tamper":
        path.write_bytes(data[:-10] + bytes(b ^ 0xFF for b in data[-10:]))
    elif edit == "bad_json":
        record.write_text(record.read_text()[:40])
    elif edit == "no_record":
        record.unlink()
    else:
        key, value = {
            "format": ("format", "simlunar-learned-map/1"),
            "features": ("feature_names", meta["feature_names"][:-1]),
            "sklearn_version": ("versions", {**meta["versions"], "scikit-learn": "0.1"}),
        }[edit]
        record.write_text(json.dumps({**meta, key: value}))
    with pytest.raises(ValueError, match=match) as err:
        LearnedReconstruction.load(path)
    msg = str(err.value)
    assert "\n" not in msg and str(path.with_suffix("")) in msg  # one line naming the file


def test_map_and_reconstruction_files_refuse_each_other(model, tmp_path):
    pairs = [planted_pair(0, shape=(32, 32))]
    lmap = train_learned_map(
        pairs, densities=[1 / 16], options=LearnedOptions(pixels_per_example=500, max_iter=5), rng=0
    )
    map_path, _ = lmap.save(tmp_path / "map.joblib")
    rec_path, _ = model.save(tmp_path / "rec.joblib")
    with pytest.raises(ValueError, match="not a simlunar-learned-reconstruction/1"):
        LearnedReconstruction.load(map_path)
    with pytest.raises(ValueError, match="not a simlunar-learned-map/1"):
        LearnedMap.load(rec_path)


def test_registered_by_name_and_cached_per_path_and_hash(model, held_out, tmp_path):
    entry = RECONSTRUCTIONS["learned"]
    assert entry.meta == {"guided": True, "needs_model": True, "results_version": 2}
    path, _ = model.save(tmp_path / "r.joblib")
    img, z = held_out[2]
    pts, vals = layout(z, 1 / 32, 9)
    got = run_reconstruction(
        "learned", pts, vals, z.shape, guide=Guide(img), options={"model": str(path)}
    )
    want = model.reconstruct(pts, vals, z.shape, guide=Guide(img))
    np.testing.assert_array_equal(got.heights, want.heights)
    assert (
        got.info["model_sha256"]
        == json.loads(path.with_suffix(".json").read_text())["model_sha256"][:12]
    )
    first = lr._cached(path)
    assert lr._cached(str(path)) is first
    other = train_learned_reconstruction(
        [planted_pair(5, shape=(40, 48))],
        densities=[1 / 16],
        options=LearnedOptions(layouts=1, pixels_per_example=500, max_iter=5),
        rng=1,
    )
    other.save(path)  # same path, other content: loaded again
    assert lr._cached(path) is not first


def test_registry_errors_are_clear(model, tmp_path):
    img, z = planted_pair(0, shape=(30, 40))
    pts, vals = layout(z, 1 / 8, 0)
    with pytest.raises(ValueError, match="needs option 'model'"):
        run_reconstruction("learned", pts, vals, z.shape, guide=Guide(img))
    with pytest.raises(ValueError, match="needs the guide"):
        run_reconstruction("learned", pts, vals, z.shape, options={"model": "m.joblib"})
    with pytest.raises(ValueError, match="not found"):
        run_reconstruction(
            "learned",
            pts,
            vals,
            z.shape,
            guide=Guide(img),
            options={"model": str(tmp_path / "x.joblib")},
        )
    with pytest.raises(ValueError, match=r"\.joblib"):
        run_reconstruction(
            "learned", pts, vals, z.shape, guide=Guide(img), options={"model": "m.pkl"}
        )
    path, _ = model.save(tmp_path / "m.joblib")
    with pytest.raises(ValueError, match="guide image has shape"):
        model.reconstruct(pts, vals, (30, 41), guide=Guide(img))
    with pytest.raises(ValueError, match="threads"):
        LearnedReconOptions(model=str(path), threads=0)
    with pytest.raises(ValueError, match="model must be a path"):
        LearnedReconOptions(model=3)


def test_shading_feature_needs_a_registered_shading(monkeypatch):
    monkeypatch.delitem(RECONSTRUCTIONS._entries, "shading", raising=False)
    pairs = [planted_pair(0, shape=(32, 40))]
    with pytest.raises(ValueError, match="'shading', which is not registered"):
        train_learned_reconstruction(pairs, densities=[1 / 16], with_shading=True, rng=0)
    m = LearnedReconstruction(None, {"with_shading": True})
    img, z = pairs[0]
    pts, vals = layout(z, 1 / 8, 0)
    with pytest.raises(ValueError, match="'shading', which is not registered"):
        m.reconstruct(pts, vals, z.shape, guide=Guide(img))


def test_shading_feature_comes_from_the_registered_reconstruction(monkeypatch, tmp_path):
    """A stand-in ``shading`` that knows the fine relief (as the integrated slope would)."""
    from dataclasses import dataclass

    from simlunar.reconstruction.base import Reconstructed
    from simlunar.registry import option

    @dataclass(frozen=True)
    class ShadeOpts:
        gain: float = option(1.0, doc="gain")

    calls = []

    def shading(points_rc, values, shape, *, guide, options):
        calls.append(options.gain)
        lin = reconstruct(points_rc, values, shape)
        d = (guide.image - 0.5) / 0.15
        return Reconstructed(anchor(lin, options.gain * d, np.asarray(points_rc)))

    monkeypatch.setitem(RECONSTRUCTIONS._entries, "shading", Entry("shading", shading, ShadeOpts))
    pairs = [planted_pair(s, shape=(40, 48)) for s in range(2)]
    opts = LearnedOptions(layouts=1, pixels_per_example=800, max_iter=15)
    with pytest.raises(ValueError, match="unknown option 'gian'"):
        train_learned_reconstruction(
            pairs,
            densities=[1 / 16],
            options=opts,
            with_shading=True,
            shading_options={"gian": 1},
            rng=0,
        )
    m = train_learned_reconstruction(
        pairs,
        densities=[1 / 16],
        options=opts,
        with_shading=True,
        shading_options={"gain": 0.5},
        rng=0,
    )
    assert m.meta["feature_names"][-1] == "shading_detail" and m.meta["shading_options"] == {
        "gain": 0.5
    }
    path, _ = m.save(tmp_path / "s.joblib")
    calls.clear()
    img, z = planted_pair(9, shape=(40, 48))
    pts, vals = layout(z, 1 / 16, 0)
    run_reconstruction(
        "learned", pts, vals, z.shape, guide=Guide(img), options={"model": str(path)}
    )
    # the recorded shading options, at reconstruction too (twice: all the samples, then the
    # held-out check's 4/5)
    assert calls == [0.5, 0.5]


def test_check_model_file_reads_the_record_without_unpickling(model, tmp_path, no_unpickling):
    path, record = model.save(tmp_path / "m.joblib")
    got, meta = lr.check_model_file(str(path))
    assert got == path and meta == json.loads(record.read_text())


#: the noise fields of the statistical checks (``_NoiseModel(salt)``)
NOISE_SALTS = tuple(0.5 + 0.37 * i for i in range(8))


class _NoiseModel:
    """A "model" whose residual is pure noise: a fixed unit-variance field, the same at every
    call (so the held-out check's second prediction sees the same noise), unrelated to the
    truth. Each cell's value is a hash of its image gradient at scale 1 (a feature that does
    not depend on the samples), so a prediction of some cells alone gives the same values;
    ``salt`` draws another field."""

    def __init__(self, salt: float = 0.5):
        self.salt = salt

    def predict(self, x):
        from scipy.special import ndtri

        g = x[:, feature_names().index("image_grad_s1")].astype(np.float64)
        u = np.modf(np.abs(np.sin(g * 12989.8 + self.salt)) * 43758.5453)[0]
        return ndtri(np.clip(u, 1e-9, 1 - 1e-9))


def test_heldout_check_returns_linear_for_a_noise_residual(model):
    # 128 x 192 cells: 150-770 held-out samples per layout, so the check's weight of pure
    # noise is ~0 to within its sampling error (on 64 x 96 cells, ~40 held out: 0.987x seen)
    terrains = [planted_pair(s, shape=(128, 192)) for s in range(100, 103)]
    noise = LearnedReconstruction(_NoiseModel(), model.meta)
    for d in DENSITIES:
        unchecked = gains(_recon(noise), terrains, d)
        checked = gains(_recon(noise, check=True), terrains, d)
        assert max(unchecked) < 0.9, unchecked  # without the check the noise costs
        # with it: linear's MSE within 1 % (the check's weight is ~0 for noise)
        np.testing.assert_allclose(checked, 1.0, atol=0.01)


def test_heldout_check_keeps_the_gain_of_a_planted_relation(model, held_out):
    img, z = held_out[0]
    pts, vals = layout(z, DENSITIES[0], 3)
    out = model.reconstruct(pts, vals, z.shape, guide=Guide(img), heldout_check=True)
    assert out.info["heldout_samples"] >= 20 and out.info["gamma"] > 0.8
    np.testing.assert_allclose(out.heights[pts[:, 0], pts[:, 1]], vals, atol=1e-9)
    for d in (*DENSITIES, 1 / 48):
        g = gains(_recon(model, check=True), held_out, d)
        assert min(g) >= MIN_GAIN, (d, g)


def test_heldout_check_predicts_again_without_the_left_out_samples(model, held_out):
    img, z = held_out[1]
    pts, vals = layout(z, DENSITIES[1], 4)
    seen = []

    class Spy:
        def predict(self, x):
            seen.append(x[:, feature_names().index("log2_density")][0])
            return model.model.predict(x)

    spy = LearnedReconstruction(Spy(), model.meta)
    spy.reconstruct(pts, vals, z.shape, guide=Guide(img), heldout_check=True)
    # two predictions: all samples, then 4/5 of them (one in five left out)
    assert len(seen) == 2
    n_keep = len(pts) - len(range(0, len(pts), 5))
    np.testing.assert_allclose(2.0 ** np.array(seen) * z.size, [len(pts), n_keep], rtol=1e-5)


def test_registered_learned_runs_the_check_by_default(model, tmp_path):
    assert LearnedReconOptions(model="m.joblib").heldout_check is True
    img, z = planted_pair(102, shape=(128, 192))  # enough held-out samples (see above)
    pts, vals = layout(z, DENSITIES[0], 5)
    lin = reconstruct(pts, vals, z.shape)
    ratios = []
    for i, salt in enumerate(NOISE_SALTS):  # 8 noise fields: a statistical property
        path, _ = LearnedReconstruction(_NoiseModel(salt), model.meta).save(
            tmp_path / f"noise{i}.joblib"
        )
        on = run_reconstruction("learned", pts, vals, z.shape, guide=Guide(img),
                                options={"model": str(path)})  # fmt: skip
        off = run_reconstruction("learned", pts, vals, z.shape, guide=Guide(img),
                                 options={"model": str(path), "heldout_check": False})  # fmt: skip
        mse = [np.mean((h - z) ** 2) for h in (lin, on.heights, off.heights)]
        assert mse[0] < mse[2]  # the unchecked noise residual always harms
        ratios.append(mse[1] / mse[0])
        assert "gamma" in on.info and "gamma" not in off.info
    # measured over these fields: 0.999-1.017, median 1.000
    assert np.median(ratios) <= 1.01 and max(ratios) < 1.05


def test_heldout_check_pools_its_splits_on_a_sparse_layout(model, held_out):
    # 64 x 96 cells at 1/96: 64 samples, one split leaves ~13 inside the hull (shading's
    # check returns 0 there); pooled over the five splits the planted relation keeps its gain
    from simlunar.reconstruction._anchor import linear_field
    from simlunar.reconstruction.heldout import heldout_gamma

    img, z = held_out[0]
    pts, vals = layout(z, 1 / 96, 2)
    lin = linear_field(pts, vals, z.shape)
    r = model._residual(pts, vals, z.shape, Guide(img), 1)[0]
    assert heldout_gamma(r, lin) == (0.0, heldout_gamma(r, lin)[1])
    assert heldout_gamma(r, lin)[1] < 20
    out = model.reconstruct(pts, vals, z.shape, guide=Guide(img), heldout_check=True)
    assert out.info["heldout_samples"] >= 20 and out.info["gamma"] > 0.5
    lin_mse = np.mean((lin.heights - z) ** 2)
    assert np.mean((out.heights - z) ** 2) < 0.5 * lin_mse
    # a noise residual on the same sparse layout stays near linear, over 8 noise fields (60
    # held-out samples: a weight of a few per cent gets through; measured 0.997-1.163, mean
    # 1.05; one field alone decides nothing)
    ratios = []
    for salt in NOISE_SALTS:
        noise = LearnedReconstruction(_NoiseModel(salt), model.meta)
        got = noise.reconstruct(pts, vals, z.shape, guide=Guide(img), heldout_check=True)
        ratios.append(np.mean((got.heights - z) ** 2) / lin_mse)
    assert np.mean(ratios) < 1.07 and max(ratios) < 1.25


def test_the_check_predicts_only_the_sample_cells_and_changes_nothing(model, held_out, monkeypatch):
    # the check reads each remade residual at the samples alone: predicting only there must
    # give bit for bit what the full-grid predictions gave (pooled sparse folds and one split)
    from simlunar.reconstruction import learned as learned_mod

    img, z = held_out[2]
    for density, seed in ((DENSITIES[0], 7), (1 / 96, 8)):
        pts, vals = layout(z, density, seed)
        rows: list[int] = []

        class Spy:
            def __init__(self, sink):
                self.sink = sink

            def predict(self, x):
                self.sink.append(len(x))
                return model.model.predict(x)

        spy = LearnedReconstruction(Spy(rows), model.meta)
        fast = spy.reconstruct(pts, vals, z.shape, guide=Guide(img), heldout_check=True)
        assert rows[0] == z.size and all(n == len(np.unique(pts, axis=0)) for n in rows[1:])
        monkeypatch.setattr(learned_mod, "_sample_cells", lambda p, s: None)
        full = model.reconstruct(pts, vals, z.shape, guide=Guide(img), heldout_check=True)
        monkeypatch.undo()
        np.testing.assert_array_equal(fast.heights, full.heights)
        assert fast.info == full.info


def test_sample_cells_only_for_samples_on_cell_centres():
    from simlunar.reconstruction.learned import _sample_cells

    pts = np.array([[0.0, 1.0], [2.0, 3.0], [0.0, 1.0]])
    np.testing.assert_array_equal(_sample_cells(pts, (4, 5)), [1, 13])
    assert _sample_cells(pts + 0.5, (4, 5)) is None  # read bilinearly: neighbours too
    assert _sample_cells(np.array([[4.0, 0.0]]), (4, 5)) is None  # off the grid
