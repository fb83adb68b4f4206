"""The study protocol runs every configured reconstruction on every acquisition, with the guide."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from simlunar.reconstruction import RECONSTRUCTIONS, Guide, Reconstructed, reconstruct
from simlunar.registry import check_bounds, option
from simlunar.sensors.base import Acquisition
from simlunar.study.protocol import (
    Outcome,
    Trials,
    guide_cost,
    reconstruction_of,
    reconstruction_options,
    run_protocol,
)


@dataclass(frozen=True)
class _OffsetOptions:
    """A test-only guided reconstruction: linear + gain * (guide image - its mean)."""

    gain: float = option(0.5, doc="image gain", ge=0)

    def __post_init__(self):
        check_bounds(self)


def _offset(points_rc, values, shape, *, guide=None, options=None):
    base = reconstruct(points_rc, values, shape)
    img = guide.image - guide.image.mean()
    info = {"shading_share": float(options.gain), "frames": guide.frames[:1], "note": "test"}
    return Reconstructed(base + options.gain * img, info)


@pytest.fixture
def guided():
    """Register the test reconstruction for one test (the registry is global)."""
    RECONSTRUCTIONS.register("test_offset", _offset, _OffsetOptions, guided=True)
    yield "test_offset"
    del RECONSTRUCTIONS._entries["test_offset"]


class _Truth:
    name = "truth"
    needs_plan = True

    def __init__(self, depth):
        self.depth = depth

    def acquire(self, rc, *, rng=None):
        rc = np.asarray(rc)
        return Acquisition(rc, self.depth[rc[:, 0], rc[:, 1]], self.depth.shape, 1, 0.0)


def _scene():
    r, c = np.mgrid[0:24, 0:20]
    depth = np.sin(r / 4.0) + np.cos(c / 3.0)
    image = 0.5 + 0.2 * np.cos(r / 4.0)
    return depth, image


def _trials(ks=(40, 80), trials=2):
    def planner(k, rng):
        g = np.random.default_rng(rng)
        cells = g.choice(24 * 20, size=k, replace=False)
        return np.stack(np.unravel_index(cells, (24, 20)), axis=-1)

    return Trials({"random": planner}, list(ks), trials, lambda lb, t, b: (t * 10 + b, None))


def _mse(depth):
    return lambda recon, acq: {"mse": float(np.mean((recon - depth) ** 2))}


def test_default_is_linear_alone_and_scores_equal_the_direct_reconstruction():
    depth, _ = _scene()
    outs = [o for task in run_protocol(_Truth(depth), _trials(), _mse(depth)) for o in task]
    assert len(outs) == 4
    for o in outs:
        assert list(o.recon_scores) == ["linear"]
        assert o.scores is o.recon_scores["linear"]
        assert o.recon_info["linear"] == {"guide_frames": (), "exposures": 0}
        recon = reconstruct(o.acquisition.rc, o.acquisition.values, depth.shape)
        assert o.scores["mse"] == np.mean((recon - depth) ** 2)


def test_every_reconstruction_runs_on_the_same_samples_with_the_guide(guided):
    depth, image = _scene()
    guide = Guide(image, frames=("sun", "camera"))
    recons = {"linear": None, guided: {"gain": 2.0}}
    outs = [
        o
        for task in run_protocol(
            _Truth(depth), _trials(), _mse(depth), reconstructions=recons, guide=guide
        )
        for o in task
    ]
    for o in outs:
        assert list(o.recon_scores) == ["linear", guided]
        acq = o.acquisition
        lin = reconstruct(acq.rc, acq.values, depth.shape)
        expect = lin + 2.0 * (image - image.mean())
        assert o.recon_scores[guided]["mse"] == pytest.approx(np.mean((expect - depth) ** 2))
        assert o.recon_scores["linear"]["mse"] == pytest.approx(np.mean((lin - depth) ** 2))
        info = o.recon_info[guided]
        # the frames it names (one of the guide's two): one exposure; other info kept
        assert info["guide_frames"] == ("sun",) and info["exposures"] == 1
        assert info["shading_share"] == 2.0 and info["note"] == "test"


def test_workers_give_the_serial_scores_for_every_reconstruction(guided):
    depth, image = _scene()
    kw = {"reconstructions": ["linear", guided], "guide": Guide(image)}
    serial = [o for t in run_protocol(_Truth(depth), _trials(), _mse(depth), **kw) for o in t]
    forked = [
        o for t in run_protocol(_Truth(depth), _trials(), _mse(depth), workers=2, **kw) for o in t
    ]
    assert [o.recon_scores for o in serial] == [o.recon_scores for o in forked]
    assert [o.recon_info for o in serial] == [o.recon_info for o in forked]


def test_guided_without_guide_and_bad_names_are_errors(guided):
    depth, _ = _scene()
    with pytest.raises(ValueError, match="needs the guide image"):
        run_protocol(_Truth(depth), _trials(), _mse(depth), reconstructions=[guided])
    with pytest.raises(ValueError, match="unknown reconstruction 'lienar'; valid: linear"):
        reconstruction_options(["lienar"])
    with pytest.raises(ValueError, match="unknown option 'gian'"):
        reconstruction_options({guided: {"gian": 1.0}})
    with pytest.raises(ValueError, match="gain must be >= 0"):
        reconstruction_options({guided: {"gain": -1.0}})
    with pytest.raises(ValueError, match="distinct"):
        reconstruction_options(["linear", "linear"])


def test_linear_takes_the_outside_policy_unless_its_options_name_one():
    assert reconstruction_options(None, outside="nan")["linear"].outside == "nan"
    got = reconstruction_options({"linear": {"outside": "nearest"}}, outside="nan")
    assert got["linear"].outside == "nearest"


def test_guide_cost_counts_frames(guided):
    g = Guide(np.ones((3, 3)), frames=("sun", "camera", "sun_60"))
    assert guide_cost("linear", g, {}) == ((), 0)  # image-free: no exposure
    assert guide_cost(guided, g, {}) == (("sun", "camera", "sun_60"), 3)  # all by default
    assert guide_cost(guided, g, {"frames": "sun+camera"}) == (("sun", "camera"), 2)
    assert guide_cost(guided, None, {}) == ((), 0)


def test_an_outcome_without_reconstructions_is_linear():
    acq = Acquisition(np.zeros((0, 2)), np.zeros(0), (2, 2), 0, 0.0)
    o = Outcome("x", 0, 0, 3, acq, {"mse": 1.0})
    assert o.recon_scores == {"linear": {"mse": 1.0}}
    assert o.recon_info == {"linear": {"guide_frames": (), "exposures": 0}}


def test_a_labelled_reconstruction_runs_its_entry_with_its_own_options(guided):
    depth, image = _scene()
    recons = {"bright": {"reconstruction": guided, "gain": 2.0}, guided: {"gain": 0.0}}
    opts = reconstruction_options(recons)
    assert list(opts) == ["bright", guided] and opts["bright"].gain == 2.0
    assert reconstruction_of(opts["bright"]) == guided
    out = next(
        run_protocol(
            _Truth(depth), _trials(ks=(40,), trials=1), _mse(depth),
            reconstructions=recons, guide=Guide(image),
        )
    )[0]  # fmt: skip
    assert set(out.recon_scores) == {"bright", guided}
    # gain 0 is linear; gain 2 adds twice the image's detail: a different, worse score here
    assert out.recon_scores[guided]["mse"] != out.recon_scores["bright"]["mse"]
    assert out.recon_info["bright"]["shading_share"] == 2.0
    with pytest.raises(ValueError, match="label 'linear' is the name of another"):
        reconstruction_options({"linear": {"reconstruction": guided}})
    with pytest.raises(ValueError, match="unknown reconstruction 'nope'"):
        reconstruction_options({"x": {"reconstruction": "nope"}})
