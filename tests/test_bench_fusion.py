"""The fusion benchmark runs its full code path at the smoke size (so it cannot rot)."""

from __future__ import annotations

import bench_fusion  # benchmarks/ is on the path (tests/conftest.py)


def test_fusion_benchmark_smoke():
    fig = bench_fusion.fusion(smoke=True)
    assert fig["cells"] == 200 * 320
    for key in ("reference_s", "ours_s", "photoclinometry_s", "smoothed_s", "shading_flash_s",
                "shading_flash_refine_s"):  # fmt: skip
        assert fig[key] > 0
    # the lit scene at 1/256: the image-anchored methods beat linear even at this size
    assert fig["shading_gain"] > 1.0 and fig["photoclinometry_gain"] > 1.0
    assert set(bench_fusion.BENCHMARKS) == {"fusion", "learned_check"}
