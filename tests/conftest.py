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
# helpers shared by test folders (browser.py: headless Chromium)
_HELPERS = str(Path(__file__).resolve().parent)
for _path in (_FAKES, _REFERENCES, _HELPERS):
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


#: the shipped experiment files
EXPERIMENTS_DIR = Path(__file__).resolve().parents[1] / "experiments"


@pytest.fixture(scope="session")
def _shipped_models_dir(tmp_path_factory) -> Path:
    """A working folder holding every learned-model file the shipped experiments name.

    The real models are results (``simlunar train``, seconds to minutes), never committed, so a
    fresh clone has none and the experiments that name one stop at their input check. These
    are real model files of the same format, trained here in about a second on small
    synthetic pairs: enough for the checks (which hash and read them), not for science.
    """
    import re

    from scipy import ndimage

    from simlunar.features.learned import LearnedOptions
    from simlunar.planner.learning import train_learned_map

    gen = np.random.default_rng(7)
    pairs = []
    for _ in range(2):
        z = ndimage.gaussian_filter(gen.standard_normal((48, 64)), 3) * 5
        img = np.clip(0.5 + ndimage.gaussian_filter(gen.standard_normal((48, 64)), 1), 0.01, 1)
        pairs.append((img, z))
    opts = LearnedOptions(pixels_per_example=500, max_iter=5)
    model = train_learned_map(pairs, densities=[1 / 16], options=opts, rng=0)
    root = tmp_path_factory.mktemp("work")
    text = "".join(p.read_text() for p in EXPERIMENTS_DIR.glob("*.yaml"))
    recon = _recon_model_paths()
    for rel in sorted(set(re.findall(r"models/[\w.-]+\.joblib", text))):
        if rel in recon:  # a learned reconstruction's model: its own format is checked
            _tiny_recon_model(pairs, opts).save(root / rel)
        else:
            model.save(root / rel)
    return root


def _recon_model_paths() -> set[str]:
    """The model files the shipped experiments name as a learned reconstruction's."""
    from simlunar.config.loading import load_experiment, to_plain
    from simlunar.pipeline.inputs import _declared

    out = set()
    for path in EXPERIMENTS_DIR.glob("*.yaml"):
        plain = to_plain(load_experiment(path))
        for key, (marker, value) in _declared(plain).items():
            if marker.kind == "model" and key.startswith("study.reconstructions."):
                out.add(str(value))
    return out


def _tiny_recon_model(pairs, opts):
    from simlunar.planner.learning import train_learned_reconstruction

    return train_learned_reconstruction(
        [(img, z * 4) for img, z in pairs], densities=(1 / 16,), options=opts, rng=0
    )


@pytest.fixture
def with_shipped_models(_shipped_models_dir, monkeypatch) -> Path:
    """Run the test in a working folder with the shipped experiments' model files."""
    monkeypatch.chdir(_shipped_models_dir)
    return _shipped_models_dir
