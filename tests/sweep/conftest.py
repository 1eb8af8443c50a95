"""Sweep fixtures: the runner tests' offline plugin (a copy beside the sweep) and a small synthetic release."""

from __future__ import annotations

from pathlib import Path

import pytest

from povagent.testing.pytest_plugin import write_release


@pytest.fixture(scope="session")
def sweep_release(tmp_path_factory) -> Path:
    """2 houses, 2 pairs, 4 (pair, direction)s, 3 frames: 4 instances per condition."""
    return write_release(tmp_path_factory.mktemp("sweep-release") / "povbench", houses=2, pairs=2, pair_directions=4, frames=3)


@pytest.fixture
def offline_plugin(povagent_host, offline_plugin_file):
    """The offline test plugin module (copied into the test's folder) with its call counter reset."""
    from povagent.plugins import _import_module_or_file

    module = _import_module_or_file(str(offline_plugin_file))
    module.CALLS["count"] = 0
    module.FlakyBackend.SCRIPT.clear()
    return module
