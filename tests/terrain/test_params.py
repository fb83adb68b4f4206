"""Terrain parameters: every bound with its key path and the interval it prints, grid extent and
scaling by hand, the population's law checked at construction."""

from __future__ import annotations

import pytest

from simlunar.terrain.params import (
    AlbedoParams,
    BedParams,
    CraterParams,
    FractalParams,
    ParamError,
    RockParams,
    TerrainParams,
)


def test_defaults_build():
    p = TerrainParams()
    assert (p.rows, p.cols, p.spacing, p.origin) == (256, 256, 0.2, (0.0, 0.0))
    assert p.craters.law == "trask" and p.rocks.law == "intercrater"
    assert callable(p.craters.law_fn()) and callable(p.rocks.law_fn())


@pytest.mark.parametrize(
    ("make", "key", "problem"),
    [
        (lambda: FractalParams(hurst=1.0), "fractal.hurst",
         "must be a finite number in (0.0, 1.0), got 1.0"),
        (lambda: FractalParams(rms=-0.1), "fractal.rms_m",
         "must be a finite number in [0.0, inf), got -0.1"),
        (lambda: FractalParams(rolloff=0), "fractal.rolloff_m",
         "must be a finite number in (0.0, inf), got 0.0"),
        (lambda: BedParams(wavelength=float("nan")), "bed.wavelength_m",
         "must be a finite number in (0.0, inf), got nan"),
        (lambda: AlbedoParams(mean=0), "albedo.mean",
         "must be a finite number in (0.0, 1.0], got 0.0"),
        (lambda: AlbedoParams(ejecta_brightening=5.5), "albedo.ejecta_brightening",
         "must be a finite number in [0.0, 5.0], got 5.5"),
        (lambda: RockParams(albedo_contrast=-1), "rocks.albedo_contrast",
         "must be a finite number in [-0.9, 5.0], got -1.0"),
        (lambda: RockParams(mean_per_cluster=0.5), "rocks.mean_per_cluster",
         "must be a finite number in [1.0, inf), got 0.5"),
        (lambda: CraterParams(diffusivity="fast"), "craters.diffusivity_m2_per_myr",
         "must be a number, got 'fast'"),
        (lambda: CraterParams(d_min=0), "craters.d_min_m",
         "must be a finite number in (0.0, inf), got 0.0"),
        (lambda: TerrainParams(rows=8), "grid.rows", "must be an integer >= 16, got 8"),
        (lambda: TerrainParams(cols=True), "grid.cols", "must be an integer >= 16, got True"),
        (lambda: TerrainParams(rows=32.0), "grid.rows", "must be an integer >= 16, got 32.0"),
        (lambda: TerrainParams(spacing=0), "grid.spacing_m",
         "must be a finite number in (0.0, inf), got 0.0"),
        (lambda: TerrainParams(origin=(0, float("inf"))), "grid.origin_m",
         "must be a finite number in (-inf, inf), got inf"),
        (lambda: TerrainParams().scaled(1.5), "scale",
         "must be a finite number in (0.0, 1.0], got 1.5"),
    ],
)  # fmt: skip
def test_each_bound_names_its_key(make, key, problem):
    with pytest.raises(ParamError) as info:
        make()
    assert (info.value.key, info.value.problem) == (key, problem)
    assert str(info.value) == f"{key} {problem}"
    assert isinstance(info.value, ValueError)


def test_an_empty_diameter_range_and_an_unknown_law():
    with pytest.raises(ValueError, match=(
        r"^rocks diameter range is empty: rocks\.d_max_m \(1\.0\) must exceed "
        r"rocks\.d_min_m \(2\.0\)$"
    )):  # fmt: skip
        RockParams(d_min=2.0, d_max=1.0)
    with pytest.raises(ValueError, match="moonquake"):
        CraterParams(law="moonquake")
    with pytest.raises(ValueError, match=r"grid\.origin_m must be \[x, y\], got \(1, 2, 3\)"):
        TerrainParams(origin=(1, 2, 3))


def test_extent_by_hand():
    p = TerrainParams(rows=20, cols=40, spacing=0.5, origin=(100, 50))
    assert p.origin == (100.0, 50.0)
    assert p.extent == (100.0, 120.0, 40.0, 50.0)


def test_scaling_keeps_spacing_and_statistics():
    p = TerrainParams(rows=1000, cols=1600, spacing=0.2, fractal=FractalParams(rms=0.3))
    assert p.scaled(1.0) is p
    q = p.scaled(0.25)
    assert (q.rows, q.cols, q.spacing) == (250, 400, 0.2)
    assert q.fractal == p.fractal and q.craters == p.craters
    r = p.scaled(0.001)  # never below the 16-cell minimum
    assert (r.rows, r.cols) == (16, 16)
    assert p.scaled(0.0125).cols == 20  # round(1600 * 0.0125)
