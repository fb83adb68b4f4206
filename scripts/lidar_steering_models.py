"""Scan time of plans under the three steering models (the descent camera geometry, no render):

PYTHONPATH=. python scripts/lidar_steering_models.py
"""

import numpy as np

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar import SteeringOptions, order_scan, pointing_angles, scan_timing
from simlunar.lidar.scan import guide_directions
from simlunar.planner import plan

cam = Camera(
    Intrinsics.from_fov(128, 128, 40.0),
    Pose.look_at([32.0, -32.0, 50.0], [32.0, -32.0, 0.0], up=(0.0, 1.0, 0.0)),
)
base = dict(
    max_rate_rad_s=2.0, max_accel_rad_s2=50.0, settle_s=1e-3, pulse_rate_hz=1e4, pulses_per_point=4
)
models = {
    "gimbal": SteeringOptions(**base),
    "galvanometer": SteeringOptions(**{**base, "settle_s": 3e-4}, model="galvanometer"),
    "continuous_raster": SteeringOptions(
        **base, model="continuous_raster", line_pitch_rad=1.0 / cam.intrinsics.fy
    ),
}
for k in (256, 1024):
    out = {}
    for p in ("grid", "random", "lloyd_uniform"):
        ts = {m: [] for m in models}
        for seed in range(8):
            rc = plan(p, k, weights=None, shape=(128, 128), rng=seed).rc
            a = pointing_angles(guide_directions(cam, rc), cam.pose)
            for m, o in models.items():
                ts[m].append(scan_timing(a, order_scan(a, steering=o), options=o).total_s)
        out[p] = {m: np.mean(v) for m, v in ts.items()}
    for p, d in out.items():
        print(
            k,
            p,
            " ".join(f"{m}={d[m]:.2f}s ({d[m] / out['random'][m]:.2f}x random)" for m in models),
        )
