import numpy as np
import pytest
from scipy import ndimage

from simlunar.imaging.blur import gaussian_blur, gaussian_kernel1d


@pytest.mark.parametrize("sigma", [0.4, 1.0, 2.3])
@pytest.mark.parametrize("shape", [(37, 53), (5, 7), (1, 30)])
def test_blur_equals_scipy_gaussian_filter_nearest(sigma, shape):
    # (5, 7) and (1, 30) are smaller than the kernel: every tap clamps to the edge
    img = np.random.default_rng(3).random(shape) * 10
    ours = gaussian_blur(img, sigma)
    ref = ndimage.gaussian_filter(img, sigma, mode="nearest")
    assert ours.dtype == np.float32 and ours.shape == img.shape
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-5)


def test_kernel_is_scipys_and_blur_keeps_a_constant():
    w = gaussian_kernel1d(1.5)
    assert w.size == 2 * int(4 * 1.5 + 0.5) + 1 and w.sum() == pytest.approx(1.0)
    impulse = np.zeros(31)
    impulse[15] = 1
    np.testing.assert_allclose(w, ndimage.gaussian_filter1d(impulse, 1.5)[15 - 6 : 15 + 7][::-1])
    np.testing.assert_allclose(gaussian_blur(np.full((9, 9), 0.7), 2.0), 0.7, rtol=1e-6)
    with pytest.raises(ValueError, match="sigma"):
        gaussian_blur(np.ones((4, 4)), 0.0)
    with pytest.raises(ValueError, match="2-D"):
        gaussian_blur(np.ones(4), 1.0)
