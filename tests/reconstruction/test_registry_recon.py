"""The reconstruction registry: one signature, names and options checked, the guide checked."""

import numpy as np
import pytest

from simlunar.reconstruction import (
    RECONSTRUCTIONS,
    Guide,
    LinearOptions,
    reconstruct,
    run_reconstruction,
)


def test_linear_by_name_equals_the_delaunay_function():
    rng = np.random.default_rng(0)
    pts = rng.integers(0, 20, size=(40, 2))
    vals = rng.normal(size=40)
    a = run_reconstruction("linear", pts, vals, (20, 20)).heights
    b = reconstruct(pts, vals, (20, 20))
    np.testing.assert_array_equal(a, b)
    c = run_reconstruction("linear", pts, vals, (20, 20), options={"outside": "nan"}).heights
    np.testing.assert_array_equal(c, reconstruct(pts, vals, (20, 20), outside="nan"))


def test_unknown_names_and_options_are_value_errors():
    with pytest.raises(ValueError, match=r"unknown reconstruction 'linaer'.*did you mean 'linear'"):
        run_reconstruction("linaer", [[0, 0]], [1.0], (2, 2))
    with pytest.raises(ValueError, match="outside must be one of"):
        LinearOptions(outside="zero")
    with pytest.raises(TypeError, match="takes LinearOptions"):
        run_reconstruction("linear", [[0, 0]], [1.0], (2, 2), options=object())


def test_every_entry_has_an_options_dataclass_with_defaults():
    for name, entry in RECONSTRUCTIONS.items():
        assert entry.options(), name  # every option has a default


def test_guide_checks_shapes_and_directions():
    img = np.ones((4, 5))
    g = Guide(img, light=[0, 2, 2], spacing=0.2)
    np.testing.assert_allclose(g.light, [0, 2**-0.5, 2**-0.5])
    assert g.shape == (4, 5) and not g.image.flags.writeable
    with pytest.raises(ValueError, match="flat has shape"):
        Guide(img, flat=np.ones((5, 4)))
    with pytest.raises(ValueError, match="non-zero 3-vector"):
        Guide(img, light=[0, 0, 0])
    with pytest.raises(ValueError, match="spacing"):
        Guide(img, spacing=0)
    with pytest.raises(ValueError, match="NaN"):
        Guide(np.full((2, 2), np.nan))
