"""Fixtures for the geometry tests: one small generated dataset per session (real files)."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def generated_release(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two generated houses with 12 exploration frames each, in the release layout."""
    from povagent.generate import generate_dataset

    # one folder per session, shared with the simulator's and the strategy's tests (which make
    # it the same way when they run first)
    root = tmp_path_factory.getbasetemp() / "geometric-generated" / "POVBench"
    if not (root / "meta.json").exists():
        generate_dataset(root, houses=2, seed=3, frames=12, jobs=1, progress=False)
    return root


@pytest.fixture(scope="session")
def generated_dataset(generated_release):
    """The generated dataset, loaded."""
    from povagent.dataset.loader import load_dataset

    return load_dataset(generated_release)
