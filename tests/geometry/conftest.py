"""Fixtures for the geometry tests: one small generated dataset per session (real files)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def generated_dataset(generated_release):
    """The generated dataset, loaded."""
    from povagent.dataset.loader import load_dataset

    return load_dataset(generated_release)
