"""Fixtures for the agent tests: the small generated dataset the geometry tests use (real files)."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def generated_release(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two generated houses (the same folder the geometry tests use, made once a session)."""
    from povagent.generate import generate_dataset

    root = tmp_path_factory.getbasetemp() / "geometric-generated" / "POVBench"
    if not (root / "meta.json").exists():
        generate_dataset(root, houses=2, seed=3, frames=12, jobs=1, progress=False)
    return root
