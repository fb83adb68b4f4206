"""``beam_array``: a Mitsuba sensor whose film pixels are laser beams (one pixel per beam).

Pixel ``i`` of an ``N x 1`` film traces rays from one origin into the angular profile of beam
``i`` (its unit direction and two unit tangents), so ``N`` steered beams, each with its
footprint sampled by the render's samples per pixel, render in ONE launch of any integrator
(mitransient's ``transient_path`` for the returns, Mitsuba's ``path`` for the sun). The two
uniform numbers of a film sample inside pixel ``i`` (its x fraction and its y) are mapped to
an angular offset exactly as :func:`simlunar.lidar.footprint.cone_offsets` does.

Set the beams with :func:`set_beams` (JIT arrays, not literals: no kernel recompilation
between batches of the same size). Registered on first use by :func:`register`.
"""

from __future__ import annotations

import numpy as np

from simlunar.lidar.footprint import FootprintOptions

__all__ = ["SENSOR_NAME", "register", "sensor_dict", "set_beams", "tangent_frames"]

SENSOR_NAME = "simlunar_beam_array"
_REGISTERED: list[bool] = []


def register(mi) -> None:
    """Define and register the ``beam_array`` sensor (once per process; variant set)."""
    if _REGISTERED:
        return
    import drjit as dr

    class BeamArraySensor(mi.Sensor):
        """N x 1 film; pixel i = beam i. Properties: ``profile`` ("gaussian" / "uniform"),
        ``divergence`` (full angle, rad)."""

        def __init__(self, props):
            super().__init__(props)
            self.gaussian = props.get("profile", "gaussian") == "gaussian"
            self.divergence = float(props.get("divergence", 0.0))
            n = int(self.film().size().x)
            self.n_beams = n
            z = np.zeros(n, np.float32)
            self.origins = mi.Point3f(z, z, z)
            self.dirs = mi.Vector3f(z, z, z + 1)
            self.t1 = mi.Vector3f(z + 1, z, z)
            self.t2 = mi.Vector3f(z, z + 1, z)

        def _ray(self, time, sample2):
            n = self.n_beams
            x = sample2.x * n
            cell = dr.clip(dr.floor(x), 0, n - 1)
            idx = mi.UInt32(cell)
            u1 = dr.clip(x - cell, 0.0, 1.0)
            phi = dr.two_pi * sample2.y
            if self.gaussian:
                sigma, tail = self.divergence / 4.0, float(np.exp(-4.5))
                r = sigma * dr.sqrt(-2.0 * dr.log(1.0 - u1 * (1.0 - tail)))
            else:
                r = 0.5 * self.divergence * dr.sqrt(u1)
            d = dr.gather(mi.Vector3f, self.dirs, idx)
            t1 = dr.gather(mi.Vector3f, self.t1, idx)
            t2 = dr.gather(mi.Vector3f, self.t2, idx)
            sr, cr = dr.sincos(r)
            sp, cp = dr.sincos(phi)
            direction = dr.normalize(cr * d + sr * (cp * t1 + sp * t2))
            origin = dr.gather(mi.Point3f, self.origins, idx)
            return mi.RayDifferential3f(mi.Ray3f(origin, direction, time, []))

        def sample_ray(self, time, sample1, sample2, sample3, active=True):
            return self._ray(time, sample2), mi.Spectrum(1.0)

        def sample_ray_differential(self, time, sample1, sample2, sample3, active=True):
            return self._ray(time, sample2), mi.Spectrum(1.0)

        def bbox(self):
            return mi.BoundingBox3f()

        def to_string(self):
            return f"BeamArraySensor[n_beams={self.n_beams}]"

    mi.register_sensor(SENSOR_NAME, lambda props: BeamArraySensor(props))
    _REGISTERED.append(True)


def sensor_dict(n_beams: int, film: dict, footprint: FootprintOptions) -> dict:
    """``load_dict`` entry of a beam array of ``n_beams`` beams with ``film`` (N x 1)."""
    return {
        "type": SENSOR_NAME,
        "profile": footprint.profile,
        "divergence": float(footprint.divergence_rad),
        "film": film,
        "sampler": {"type": "independent", "sample_count": int(footprint.samples)},
    }


def tangent_frames(directions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit directions (n, 3) and two unit tangents (n, 3) each, mutually orthogonal."""
    d = np.asarray(directions, float)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    helper = np.where(np.abs(d[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    t1 = np.cross(d, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    return d, t1, np.cross(d, t1)


def set_beams(mi, sensor, origin: np.ndarray, directions: np.ndarray) -> None:
    """Point the beam array's ``N`` beams (directions (N, 3); origin (3,) m shared, or (N, 3)
    one per beam: a moving platform)."""
    n = sensor.n_beams
    if directions.shape != (n, 3):
        raise ValueError(f"directions must have shape ({n}, 3), got {directions.shape}")
    d, t1, t2 = tangent_frames(directions)
    o = np.broadcast_to(np.asarray(origin, float), (n, 3))

    def vec(a, kind=mi.Vector3f):
        a = np.ascontiguousarray(a.T, dtype=np.float32)
        return kind(a[0], a[1], a[2])

    sensor.dirs, sensor.t1, sensor.t2 = vec(d), vec(t1), vec(t2)
    sensor.origins = vec(o, mi.Point3f)
