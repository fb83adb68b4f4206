"""No reconstruction reads the truth: protocol-style check over every registered name.

The truth grid is wrapped so that any read of it raises; the samples are read from it once,
beforehand (as the study's protocol does when it measures them), and handed over as plain
arrays. Every registered reconstruction then runs to completion, so none of them reaches the
truth by any path; and none accepts it by signature.
"""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from simlunar.reconstruction import RECONSTRUCTIONS, Guide, run_reconstruction
from simlunar.reconstruction.flatfield import FlashGeometry
from simlunar.reconstruction.synthetic import jittered_samples, lit_terrain


class TruthRead(AssertionError):
    pass


class Sealed:
    """The truth grid behind a seal: every read of it (indexing, conversion to an array,
    arithmetic, iteration, any attribute) raises once sealed."""

    def __init__(self, array):
        self._array = np.asarray(array)
        self._sealed = False

    def seal(self):
        self._sealed = True

    def _open(self):
        if self._sealed:
            raise TruthRead("the truth was read")
        return self._array

    def __getitem__(self, key):
        return self._open()[key]

    def __array__(self, dtype=None, copy=None):
        return np.asarray(self._open(), dtype=dtype)

    def __len__(self):
        return len(self._open())

    def __iter__(self):
        return iter(self._open())

    def __float__(self):
        return float(self._open())

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        self._open()
        return NotImplemented

    def __array_function__(self, func, types, args, kwargs):
        self._open()
        return NotImplemented

    def __getattr__(self, name):  # shape, dtype, __array_interface__, ...
        return getattr(self._open(), name)


def _arith(name):
    def op(self, *args):
        return getattr(self._open(), name)(*args)

    return op


for _op in ("add", "sub", "mul", "truediv", "pow", "lt", "le", "gt", "ge", "eq", "ne"):
    setattr(Sealed, f"__{_op}__", _arith(f"__{_op}__"))
    if _op in ("add", "sub", "mul", "truediv", "pow"):
        setattr(Sealed, f"__r{_op}__", _arith(f"__r{_op}__"))


def test_the_sealed_truth_raises_on_reads():
    t = Sealed(np.arange(6.0).reshape(2, 3))
    assert t[0, 1] == 1.0 and np.asarray(t).sum() == 15.0
    t.seal()
    reads = (lambda: t[0, 0], lambda: np.asarray(t), lambda: t + 1, lambda: np.mean(t),
             lambda: t.shape, lambda: np.float64(1.0) * t, lambda: list(t))  # fmt: skip
    for read in reads:
        with pytest.raises(TruthRead):
            read()


def _options(name, tmp_path):
    """Default options; a reconstruction that needs a model gets one trained on another
    terrain (never the sealed one)."""
    if not RECONSTRUCTIONS[name].meta.get("needs_model"):
        return None
    from simlunar.features.learned import LearnedOptions
    from simlunar.planner.learning import train_learned_reconstruction

    other = lit_terrain((48, 56), rng=5)
    opts = LearnedOptions(layouts=1, pixels_per_example=600, max_iter=10)
    model = train_learned_reconstruction(
        [(other.image, other.heights)], densities=[1 / 32], options=opts, rng=0
    )
    path, _ = model.save(tmp_path / f"{name}.joblib")
    return {"model": str(path)}


@pytest.mark.parametrize("flash", [False, True])
def test_every_reconstruction_runs_without_the_truth(tmp_path, flash):
    shape = (64, 80)
    scene = lit_terrain(shape, rng=0)
    truth = Sealed(scene.heights.copy())
    pts = jittered_samples(shape, 1 / 32, rng=1)
    values = np.array(truth[pts[:, 0], pts[:, 1]])  # measured beforehand, a plain array
    # a flash's flat: the reconstructions flat-field it on the samples' surface, not the truth
    geo = FlashGeometry(row=20.0, col=30.0, level=-30.0, beam_exponent=2.0) if flash else None
    flat = scene.flat * (0.5 + np.linspace(0, 0.5, shape[1]))[None, :] if flash else scene.flat
    guide = Guide(scene.image, light=scene.light, flat=flat, flash=geo)
    del scene  # the rendered scene holds the heights too
    truth.seal()
    assert type(values) is np.ndarray
    for name in RECONSTRUCTIONS:
        opts = _options(name, tmp_path)
        res = run_reconstruction(name, pts, values, shape, guide=guide, options=opts)
        assert res.heights.shape == shape and np.isfinite(res.heights).all(), name
        assert type(res.heights) is np.ndarray, name


def test_no_reconstruction_takes_the_truth_by_signature():
    for name, entry in RECONSTRUCTIONS.items():
        params = list(inspect.signature(entry.target).parameters)
        assert params[:3] == ["points_rc", "values", "shape"], name
        assert set(params[3:]) == {"guide", "options"}, name
