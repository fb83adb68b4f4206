"""Shared fixtures: a seeded rng and the rendering backend (initialised once per session)."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def mi():
    """Mitsuba with simlunar's variant set and plugins registered."""
    from simlunar.render import backend

    backend.init()
    return backend.mitsuba()
