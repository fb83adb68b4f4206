"""Shared fixtures: a seeded rng and the rendering backend (initialised once per session)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

# the fake work unit and CLI of tests/pipeline importable by name from any test folder (spawned
# pool workers unpickle the fake unit by reference)
_FAKES = str(Path(__file__).resolve().parent / "pipeline")
# the slow reference implementations the fast paths are checked (and benchmarked) against
_REFERENCES = str(Path(__file__).resolve().parents[1] / "benchmarks")
for _path in (_FAKES, _REFERENCES):
    if _path not in sys.path:
        sys.path.insert(0, _path)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def mi():
    """Mitsuba with simlunar's variant set and plugins registered."""
    from simlunar.render import backend

    backend.init()
    return backend.mitsuba()
