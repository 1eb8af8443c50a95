"""Sweep fixtures: the runner tests' offline plugin (by path) and a small synthetic release."""

from __future__ import annotations

from pathlib import Path

import pytest

from povagent.testing.pytest_plugin import write_release

OFFLINE_PLUGIN = str(Path(__file__).resolve().parents[1] / "run" / "offline_plugin.py")


@pytest.fixture(scope="session")
def sweep_release(tmp_path_factory) -> Path:
    """2 houses, 2 pairs, 4 (pair, direction)s, 3 frames: 4 instances per condition."""
    return write_release(tmp_path_factory.mktemp("sweep-release") / "povbench", houses=2, pairs=2, pair_directions=4, frames=3)


@pytest.fixture
def offline_plugin(povagent_host):
    """The offline test plugin module with its call counter reset."""
    from povagent.plugins import _import_module_or_file

    module = _import_module_or_file(OFFLINE_PLUGIN)
    module.CALLS["count"] = 0
    module.FlakyBackend.SCRIPT.clear()
    return module
