"""Shared fixtures: the hand-made release-layout fixture."""

from __future__ import annotations

from pathlib import Path

import pytest

# Our own fixtures for plugin authors are opt-in (no pytest11 entry point): we opt in here.
pytest_plugins = ["povagent.testing.pytest_plugin"]

FIXTURES = Path(__file__).resolve().parent / "fixtures"
MINI = FIXTURES / "povbench_mini"


@pytest.fixture(scope="session")
def mini_root() -> Path:
    """The hand-made dataset: two good houses and one broken house (train_house_00002)."""
    return MINI


@pytest.fixture(scope="session")
def mini_dataset(mini_root):
    """The hand-made dataset, loaded (the broken house is reported and skipped)."""
    from povagent.dataset import load_dataset

    return load_dataset(mini_root)
