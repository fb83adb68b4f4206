"""Figure of docs/lidar.md: a steered beam's return waveform at a rock edge.

A 1 m step (a rock's flat top beside the ground) seen from 50 m straight down by a beam of
10 mrad divergence (Gaussian, 1024 footprint rays) aimed at the edge: half the spot lands on the
top (range 49 m), half on the ground (50 m), and the transport gives two returns.
Run: ``.venv/bin/python scripts/lidar_rock_edge.py`` (writes docs/figures/lidar_rock_edge.png).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simlunar.lidar import (
    DetectorOptions,
    FootprintOptions,
    PulseOptions,
    RangeOptions,
    TimeBins,
    expected_counts,
    extract_ranges,
    photon_counts,
    shape_waveform,
)
from simlunar.plotting.lidar import waveform
from simlunar.render.lights import SunLight
from simlunar.render.transient import BeamCapture, capture_beams
from simlunar.terrain import Terrain

OUT = Path(__file__).resolve().parents[1] / "docs" / "figures" / "lidar_rock_edge.png"


def main() -> None:
    n, s = 200, 0.05
    x = -n * s / 2 + (np.arange(n) + 0.5) * s
    heights = np.broadcast_to(np.where(x > 0, 1.0, 0.0)[None, :], (n, n)).copy()
    terrain = Terrain(heights, np.full((n, n), 0.12, np.float32), s, origin=(-n * s / 2, n * s / 2))
    window = TimeBins(0.0, 0.02, 300)  # 1 cm range bins over 3 m
    sun = SunLight(elevation=np.radians(20.0), azimuth=np.radians(90.0))
    cap = BeamCapture(
        terrain,
        [0.0, 0.0, 50.0],
        footprint=FootprintOptions(0.01, samples=1024),
        window=window,
        sun=sun,
        batch=1,
    )
    # the gate: 50 m above the datum z = 0 straight down, +-1.2 m (the rock's 1 m inside it)
    ret = capture_beams(cap, np.array([[0.0, 0.0, -1.0]]), np.array([50.0]), margin_m=1.2)
    pulse = PulseOptions(fwhm_s=1e-9, jitter_s=0.1e-9)
    det = DetectorOptions(signal_photons=6e6, background_photons_per_s=3e10, pulses=20)
    lam = expected_counts(
        shape_waveform(ret.histograms, window, pulse, oversample=ret.oversample),
        ret.sun,
        window,
        det,
    )
    counts = photon_counts(lam, options=det, rng=0)
    offset = ret.start_opl[0] / 2
    found = {
        which: float(
            extract_ranges(counts, window, pulse=pulse, options=RangeOptions(which=which)).range[0]
            + offset
        )
        for which in ("first", "last", "strongest")
    }
    fig, _ = waveform(
        window.centres_range + offset,
        counts[0],
        expected=lam[0] * det.pulses,
        returns=found,
        truth={"rock top": 49.0, "ground": 50.0},
        title="1 m rock edge, 10 mrad beam from 50 m, 20 pulses, sun 20°",
    )
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=150)
    print(OUT, found)


if __name__ == "__main__":
    main()
